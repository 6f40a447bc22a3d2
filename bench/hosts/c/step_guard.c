/* Stopping a firmware's bt_step that hangs (bench/hosts/cosim.py).  Each co-simulation has a guard (bt_guard_init);
 * a bench thread runs bt_step through bt_guard_step, and a watchdog that gives up on it calls bt_guard_stop, then
 * bt_guard_poke until the step is left: the guard's signal goes to the step's thread, one at a time, and its handler
 * jumps back out of the firmware — only when the thread was interrupted in the firmware library's own code.
 *
 * Why only there: a thread interrupted inside the C library (malloc, printf) may hold one of its locks, and a jump
 * out of it leaves the lock held for good — the next malloc or printf of any thread (the interpreter's own, or the
 * process's exit flushing stdio) then waits forever.  Elsewhere the handler returns and the next signal tries again
 * (as a runtime that preempts threads by signal does: only at a safe point, else later); a step that never comes
 * back to the firmware's code (blocked in a system call, or waiting for a lock it never gets) is not left, and
 * bt_guard_outside says where it is.  The firmware is given a HAL of wrappers (bt_guard_wrap) that block the signal
 * while the bench's HAL function (Python) runs, and leave the step as that call returns once a stop was asked: the
 * jump never leaves the interpreter.  A fault in the firmware's own code (on_crash) leaves the step the same way.
 * A stop is for good: every later bt_guard_step of that guard returns 1 at once
 * (the firmware's state was left midway).  bt_init (bt_guard_start) and bt_set_pattern (bt_guard_set_pattern) run
 * under the guard too, as bt_step does.
 * The firmware's own calls of exit, _exit, abort and __assert_fail (a failed assert) are redirected to the guard
 * (bt_guard_take_exits rewrites the library's entries for them in its global offset table — any library, built by
 * the bench or not), and each guarded call runs with an alternate signal stack, so a stack overflow in the firmware
 * (unbounded recursion) reaches on_crash rather than ending the process.  The handler acts only for the guard whose
 * stop was asked, so a thread that runs two co-simulations, or two threads that run one each, stop only what was
 * asked. */
#define _GNU_SOURCE
#include <elf.h>
#include <link.h>
#include <pthread.h>
#include <setjmp.h>
#include <signal.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <ucontext.h>
#include <unistd.h>

#include "bt_hal.h"

#define MAX_TEXT 8 /* executable segments of a firmware library kept */

typedef struct {
    atomic_int stop;            /* set by bt_guard_stop: leave the step, refuse every later one */
    atomic_int inside;          /* 1 while bt_guard_step runs the step */
    atomic_int in_hal;          /* 1 while the step is inside one of the bench's HAL functions */
    atomic_uint sent, seen;     /* signals sent to the step's thread, and seen by its handler */
    atomic_uintptr_t outside;   /* where the last signal found the thread outside the firmware's code (0: none) */
    int crash_signal;           /* the firmware's code faulted: SIGSEGV, SIGBUS, SIGFPE or SIGILL (0: never) */
    int overflow;               /* that fault touched just below the thread's stack: a stack overflow */
    char exit_call[256];        /* what the firmware called that would have ended the process ("": nothing) */
    uintptr_t crash_pc, crash_addr; /* where it faulted, and the address it touched */
    pthread_t thread;           /* the thread running the step (set before inside) */
    uintptr_t lo[MAX_TEXT], hi[MAX_TEXT];
    int n_text;                 /* the firmware library's executable segments: [lo, hi) */
} bt_guard;

static _Thread_local bt_guard *current;  /* the guard whose step this thread runs */
static _Thread_local sigjmp_buf *leave;  /* where that step is left */
static _Thread_local uintptr_t stack_lo; /* the lowest address of this thread's stack (0: not known yet) */
static int guard_signal;

/* How far below its stack (bytes) a fault counts as the stack overflowing: a frame that jumps the guard page. */
#define OVERFLOW_REACH (1u << 20)
/* The alternate signal stack given to each thread that runs a firmware (bytes). */
#define ALT_STACK_BYTES (64u * 1024u)

static pthread_key_t alt_stack_key;
static pthread_once_t alt_stack_once = PTHREAD_ONCE_INIT;

/* A thread that ends: its alternate signal stack given back. */
static void drop_alt_stack(void *stack) {
    stack_t off = {.ss_flags = SS_DISABLE};
    sigaltstack(&off, NULL);
    munmap(stack, ALT_STACK_BYTES);
}

static void make_alt_stack_key(void) { pthread_key_create(&alt_stack_key, drop_alt_stack); }

/* Give this thread an alternate signal stack where it has none (a fault of a stack overflow has no stack left to run
 * its handler on: without one the process ends), and note where its stack ends. */
static void prepare_thread(void) {
    if (!stack_lo) {
        pthread_attr_t attr;
        void *addr;
        size_t size;
        if (pthread_getattr_np(pthread_self(), &attr) == 0) {
            if (pthread_attr_getstack(&attr, &addr, &size) == 0) stack_lo = (uintptr_t)addr;
            pthread_attr_destroy(&attr);
        }
    }
    stack_t now;
    if (sigaltstack(NULL, &now) != 0 || !(now.ss_flags & SS_DISABLE)) return; /* (one there already: kept) */
    pthread_once(&alt_stack_once, make_alt_stack_key);
    void *stack = mmap(NULL, ALT_STACK_BYTES, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (stack == MAP_FAILED) return;
    stack_t alt = {.ss_sp = stack, .ss_size = ALT_STACK_BYTES, .ss_flags = 0};
    if (sigaltstack(&alt, NULL) != 0) {
        munmap(stack, ALT_STACK_BYTES);
        return;
    }
    pthread_setspecific(alt_stack_key, stack);
}

static uintptr_t pc_of(void *uc) {
#if defined(__x86_64__)
    return (uintptr_t)((ucontext_t *)uc)->uc_mcontext.gregs[REG_RIP];
#elif defined(__aarch64__)
    return (uintptr_t)((ucontext_t *)uc)->uc_mcontext.pc;
#else
    (void)uc;
    return 0; /* another machine: never the firmware's code; the step is left at its next HAL call only */
#endif
}

static int in_firmware(const bt_guard *g, uintptr_t pc) {
    for (int i = 0; i < g->n_text; i++)
        if (pc >= g->lo[i] && pc < g->hi[i]) return 1;
    return 0;
}

static void on_signal(int sig, siginfo_t *info, void *uc) {
    bt_guard *g = current;
    (void)sig;
    (void)info;
    if (!g) return;
    atomic_fetch_add(&g->seen, 1);
    if (!atomic_load(&g->stop)) return;
    uintptr_t pc = pc_of(uc);
    if (in_firmware(g, pc)) siglongjmp(*leave, 1);
    atomic_store(&g->outside, pc);
}

/* A fault (SIGSEGV, SIGBUS, SIGFPE, SIGILL) in the firmware's own code, in a guarded step: the step is left and the
 * guard stopped, the fault recorded (bt_guard_step returns 2).  Anywhere else — the interpreter, the C library (whose
 * locks a jump could leave held) — the handler that was there before is put back and the fault happens again under
 * it (Python's faulthandler, or the default: the process ends as it would have). */
#define N_CRASH 4
static const int crash_signals[N_CRASH] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL};
static struct sigaction before_crash[N_CRASH];

static void on_crash(int sig, siginfo_t *info, void *uc) {
    bt_guard *g = current;
    uintptr_t pc = pc_of(uc);
    if (g && atomic_load(&g->inside) && !atomic_load(&g->in_hal) && in_firmware(g, pc)) {
        g->crash_signal = sig;
        g->crash_pc = pc;
        g->crash_addr = (uintptr_t)info->si_addr;
        g->overflow = sig == SIGSEGV && stack_lo && g->crash_addr < stack_lo
                      && g->crash_addr + OVERFLOW_REACH >= stack_lo;
        atomic_store(&g->stop, 1);
        siglongjmp(*leave, 2);
    }
    for (int i = 0; i < N_CRASH; i++)
        if (crash_signals[i] == sig) sigaction(sig, &before_crash[i], NULL);
    if (info->si_code <= 0) raise(sig); /* (sent by kill, not a fault: it would not come again by itself) */
}

/* Install on_crash for the fault signals where it is not installed already, keeping what was there to hand faults
 * elsewhere back to; 0 on success. */
int bt_guard_catch_crashes(void) {
    for (int i = 0; i < N_CRASH; i++) {
        struct sigaction sa, old;
        if (sigaction(crash_signals[i], NULL, &old) != 0) return -1;
        if ((old.sa_flags & SA_SIGINFO) && old.sa_sigaction == on_crash) continue;
        memset(&sa, 0, sizeof sa);
        sa.sa_sigaction = on_crash;
        sa.sa_flags = SA_SIGINFO | SA_ONSTACK;
        sigemptyset(&sa.sa_mask);
        before_crash[i] = old;
        if (sigaction(crash_signals[i], &sa, NULL) != 0) return -1;
    }
    return 0;
}

/* The fault that left g's step: its signal (0: none), and where (the code's address, the address touched);
 * *overflow: 1 when it was the stack overflowing. */
int bt_guard_crash(const bt_guard *g, uintptr_t *pc, uintptr_t *addr, int *overflow) {
    *pc = g->crash_pc;
    *addr = g->crash_addr;
    *overflow = g->overflow;
    return g->crash_signal;
}

/* The firmware called exit, _exit, abort or __assert_fail (what: how, said): in a guarded call (and not inside a HAL
 * function of the bench's), the call is left and the guard stopped, what recorded (bt_guard_step returns 3);
 * elsewhere it returns, and the caller goes on to the C library's function. */
static void leave_on_exit(const char *what) {
    bt_guard *g = current;
    if (!g || !atomic_load(&g->inside) || atomic_load(&g->in_hal)) return;
    strncpy(g->exit_call, what, sizeof g->exit_call - 1);
    atomic_store(&g->stop, 1);
    siglongjmp(*leave, 3);
}

static _Noreturn void guard_exit(int status) {
    char what[32];
    snprintf(what, sizeof what, "exit(%d)", status);
    leave_on_exit(what);
    exit(status);
}

static _Noreturn void guard__exit(int status) {
    char what[32];
    snprintf(what, sizeof what, "_exit(%d)", status);
    leave_on_exit(what);
    _exit(status);
}

static _Noreturn void guard_abort(void) {
    leave_on_exit("abort()");
    abort();
}

extern _Noreturn void __assert_fail(const char *assertion, const char *file, unsigned int line, const char *function);

static _Noreturn void guard_assert_fail(const char *assertion, const char *file, unsigned int line,
                                        const char *function) {
    char what[256];
    snprintf(what, sizeof what, "assert(%s), which failed at %s:%u in %s()", assertion, file, line, function);
    leave_on_exit(what);
    __assert_fail(assertion, file, line, function);
}

/* The C library's functions that end the process, and the guard's function each of the firmware's calls goes to. */
static const struct {
    const char *name;
    void *guarded;
} exit_calls[] = {
    {"exit", (void *)guard_exit},
    {"_exit", (void *)guard__exit},
    {"abort", (void *)guard_abort},
    {"__assert_fail", (void *)guard_assert_fail},
};
#define N_EXIT_CALLS (sizeof exit_calls / sizeof exit_calls[0])

/* What g's firmware called that would have ended the process ("": nothing). */
const char *bt_guard_exit_call(const bt_guard *g) { return g->exit_call; }

/* Install the handler for signal sig; 0 on success (or when it is installed already), 1 when the signal has another
 * handler in this process (left as it is: the bench never takes a signal something else uses), -1 on failure. */
int bt_guard_install(int sig) {
    struct sigaction sa, old;
    if (sigaction(sig, NULL, &old) != 0) return -1;
    if ((old.sa_flags & SA_SIGINFO) && old.sa_sigaction == on_signal) {
        guard_signal = sig;
        return 0;
    }
    if ((old.sa_flags & SA_SIGINFO) || old.sa_handler != SIG_DFL) return 1;
    memset(&sa, 0, sizeof sa);
    sa.sa_sigaction = on_signal;
    sa.sa_flags = SA_SIGINFO | SA_RESTART; /* (a system call of the firmware's it interrupts goes on) */
    sigemptyset(&sa.sa_mask);
    guard_signal = sig;
    return sigaction(sig, &sa, NULL) == 0 ? 0 : -1;
}

/* 1 while signal sig's handler is still the guard's (nothing replaced it since bt_guard_install). */
int bt_guard_installed(int sig) {
    struct sigaction now;
    return sigaction(sig, NULL, &now) == 0 && (now.sa_flags & SA_SIGINFO) && now.sa_sigaction == on_signal;
}

struct wanted {
    uintptr_t addr;
    bt_guard *g;
};

static int take_text(struct dl_phdr_info *info, size_t size, void *data) {
    struct wanted *w = data;
    int found = 0;
    (void)size;
    for (int i = 0; i < info->dlpi_phnum; i++) {
        const ElfW(Phdr) *ph = &info->dlpi_phdr[i];
        uintptr_t lo = info->dlpi_addr + ph->p_vaddr;
        if (ph->p_type == PT_LOAD && w->addr >= lo && w->addr < lo + ph->p_memsz) found = 1;
    }
    if (!found) return 0;
    for (int i = 0; i < info->dlpi_phnum && w->g->n_text < MAX_TEXT; i++) {
        const ElfW(Phdr) *ph = &info->dlpi_phdr[i];
        if (ph->p_type == PT_LOAD && (ph->p_flags & PF_X)) {
            w->g->lo[w->g->n_text] = info->dlpi_addr + ph->p_vaddr;
            w->g->hi[w->g->n_text++] = info->dlpi_addr + ph->p_vaddr + ph->p_memsz;
        }
    }
    return 1;
}

size_t bt_guard_size(void) { return sizeof(bt_guard); }

/* Make *g (bt_guard_size() bytes, zeroed) the guard of the firmware library holding the function at
 * firmware_symbol (its bt_step); 0 on success, 1 when no loaded library holds it. */
int bt_guard_init(bt_guard *g, void *firmware_symbol) {
    struct wanted w = {(uintptr_t)firmware_symbol, g};
    return dl_iterate_phdr(take_text, &w) && g->n_text > 0 ? 0 : 1;
}

/* One of the firmware's entry points and its arguments: step(state), init(state, hal), or
 * set_pattern(state, payload, n) and where its result goes. */
struct entry {
    void (*step)(void *);
    void (*init)(void *, const void *);
    uint8_t (*set_pattern)(void *, const uint8_t *, size_t);
    void *state;
    const void *hal;
    const uint8_t *payload;
    size_t n;
    uint8_t *result;
};

#if defined(__x86_64__)
#define R_JUMP_SLOT R_X86_64_JUMP_SLOT
#define R_GLOB_DAT R_X86_64_GLOB_DAT
#elif defined(__aarch64__)
#define R_JUMP_SLOT R_AARCH64_JUMP_SLOT
#define R_GLOB_DAT R_AARCH64_GLOB_DAT
#endif

struct exits_wanted {
    uintptr_t addr; /* an address inside the firmware library */
    int rewritten;  /* entries of its global offset table pointed at the guard's functions (-1: none could be) */
};

/* Point the library's entries for exit_calls (relocations list) at the guard's functions; entries in its read-only
 * part (RELRO) are made writable for the write.  How many were rewritten. */
static int rewrite_entries(uintptr_t base, const ElfW(Rela) *rel, size_t bytes, const ElfW(Sym) *symbols,
                           const char *names, uintptr_t relro_lo, uintptr_t relro_hi) {
    int rewritten = 0;
#ifdef R_JUMP_SLOT
    uintptr_t page = (uintptr_t)sysconf(_SC_PAGESIZE);
    for (size_t i = 0; i < bytes / sizeof *rel; i++) {
        unsigned type = ELF64_R_TYPE(rel[i].r_info);
        if (type != R_JUMP_SLOT && type != R_GLOB_DAT) continue;
        const char *name = names + symbols[ELF64_R_SYM(rel[i].r_info)].st_name;
        for (size_t k = 0; k < N_EXIT_CALLS; k++) {
            if (strcmp(name, exit_calls[k].name) != 0) continue;
            uintptr_t slot = base + rel[i].r_offset;
            /* (the loader makes read-only the whole pages inside RELRO: a last part page stays writable) */
            int locked = slot >= (relro_lo & ~(page - 1)) && slot < (relro_hi & ~(page - 1));
            void *first = (void *)(slot & ~(page - 1));
            if (locked && mprotect(first, page, PROT_READ | PROT_WRITE) != 0) break;
            *(void *volatile *)slot = exit_calls[k].guarded;
            if (locked) mprotect(first, page, PROT_READ);
            rewritten++;
        }
    }
#else
    (void)base, (void)rel, (void)bytes, (void)symbols, (void)names, (void)relro_lo, (void)relro_hi, (void)exit_calls;
#endif
    return rewritten;
}

static int take_exits(struct dl_phdr_info *info, size_t size, void *data) {
    struct exits_wanted *w = data;
    const ElfW(Dyn) *dyn = NULL;
    uintptr_t base = info->dlpi_addr, relro_lo = 0, relro_hi = 0;
    int found = 0;
    (void)size;
    for (int i = 0; i < info->dlpi_phnum; i++) {
        const ElfW(Phdr) *ph = &info->dlpi_phdr[i];
        uintptr_t lo = base + ph->p_vaddr;
        if (ph->p_type == PT_LOAD && w->addr >= lo && w->addr < lo + ph->p_memsz) found = 1;
        if (ph->p_type == PT_DYNAMIC) dyn = (const ElfW(Dyn) *)lo;
        if (ph->p_type == PT_GNU_RELRO) relro_lo = lo, relro_hi = lo + ph->p_memsz;
    }
    if (!found) return 0;
    if (!dyn) return 1;
    const ElfW(Sym) *symbols = NULL;
    const char *names = NULL;
    const ElfW(Rela) *plt = NULL, *rela = NULL;
    size_t plt_bytes = 0, rela_bytes = 0;
    long plt_kind = DT_RELA;
    for (; dyn->d_tag != DT_NULL; dyn++) {
        /* (the loader has made most of these addresses absolute already; an offset is below the library's base) */
        uintptr_t at = dyn->d_un.d_ptr < base ? base + dyn->d_un.d_ptr : dyn->d_un.d_ptr;
        switch (dyn->d_tag) {
        case DT_SYMTAB: symbols = (const ElfW(Sym) *)at; break;
        case DT_STRTAB: names = (const char *)at; break;
        case DT_JMPREL: plt = (const ElfW(Rela) *)at; break;
        case DT_PLTRELSZ: plt_bytes = dyn->d_un.d_val; break;
        case DT_PLTREL: plt_kind = (long)dyn->d_un.d_val; break;
        case DT_RELA: rela = (const ElfW(Rela) *)at; break;
        case DT_RELASZ: rela_bytes = dyn->d_un.d_val; break;
        default: break;
        }
    }
    if (!symbols || !names || plt_kind != DT_RELA) return 1;
    w->rewritten = (plt ? rewrite_entries(base, plt, plt_bytes, symbols, names, relro_lo, relro_hi) : 0)
                   + (rela ? rewrite_entries(base, rela, rela_bytes, symbols, names, relro_lo, relro_hi) : 0);
    return 1;
}

/* Send the firmware library's own calls of exit, _exit, abort and __assert_fail (the library holding the function at
 * firmware_symbol) to the guard: in a guarded call they leave it (bt_guard_exit_call says what was called), elsewhere
 * they go on to the C library.  How many of its entries were rewritten (0: it calls none of them), -1 when no loaded
 * library holds firmware_symbol or this machine's relocations are not known here. */
int bt_guard_take_exits(void *firmware_symbol) {
    struct exits_wanted w = {(uintptr_t)firmware_symbol, -1};
#ifdef R_JUMP_SLOT
    dl_iterate_phdr(take_exits, &w);
#else
    (void)take_exits;
#endif
    return w.rewritten;
}

/* Run call under guard g; 0 when it returned, 1 when it was left (bt_guard_stop) or a stop was asked before, 2 when
 * it faulted in the firmware's code (bt_guard_crash), 3 when it called exit or the like (bt_guard_exit_call). */
static int run_guarded(bt_guard *g, const struct entry *call) {
    sigjmp_buf env;
    prepare_thread();
    g->thread = pthread_self();
    current = g;
    leave = &env;
    int left = sigsetjmp(env, 1);
    if (left) {
        atomic_store(&g->inside, 0);
        current = NULL;
        return left;
    }
    atomic_store(&g->inside, 1);
    if (atomic_load(&g->stop)) { /* (after inside is set: a stop is either seen here or signalled in the step) */
        atomic_store(&g->inside, 0);
        current = NULL;
        return 1;
    }
    if (call->init)
        call->init(call->state, call->hal);
    else if (call->set_pattern)
        *call->result = call->set_pattern(call->state, call->payload, call->n);
    else
        call->step(call->state);
    atomic_store(&g->inside, 0);
    current = NULL;
    return 0;
}

/* Run the firmware's step(state) under guard g (run_guarded says what comes back). */
int bt_guard_step(bt_guard *g, void (*step)(void *), void *state) {
    struct entry call = {.step = step, .state = state};
    return run_guarded(g, &call);
}

/* Run the firmware's init(state, hal) under guard g (run_guarded says what comes back). */
int bt_guard_start(bt_guard *g, void (*init)(void *, const void *), void *state, const void *hal) {
    struct entry call = {.init = init, .state = state, .hal = hal};
    return run_guarded(g, &call);
}

/* Run the firmware's set_pattern(state, payload, n) under guard g, its result in *result when it returned
 * (run_guarded says what comes back). */
int bt_guard_set_pattern(bt_guard *g, uint8_t (*set_pattern)(void *, const uint8_t *, size_t), void *state,
                         const uint8_t *payload, size_t n, uint8_t *result) {
    struct entry call = {.set_pattern = set_pattern, .state = state, .payload = payload, .n = n, .result = result};
    return run_guarded(g, &call);
}

/* Ask g's step to be left, for good. */
void bt_guard_stop(bt_guard *g) { atomic_store(&g->stop, 1); }

int bt_guard_stopped(const bt_guard *g) { return atomic_load(&g->stop); }

/* One go at leaving g's step once stopped: 0 when no step runs (left, or none was running); 2 while it is inside a
 * HAL function of the bench's (it leaves as that returns); 1 when a signal was sent, or one is on its way still. */
int bt_guard_poke(bt_guard *g) {
    if (!atomic_load(&g->inside)) return 0;
    if (atomic_load(&g->in_hal)) return 2;
    if (atomic_load(&g->sent) != atomic_load(&g->seen)) return 1; /* (one at a time: real-time signals queue) */
    atomic_fetch_add(&g->sent, 1);
    if (pthread_kill(g->thread, guard_signal) != 0) atomic_fetch_sub(&g->sent, 1);
    return 1;
}

/* Where the last signal found g's step outside the firmware's code (an address; 0: never). */
uintptr_t bt_guard_outside(const bt_guard *g) { return atomic_load(&g->outside); }

/* A HAL call of the firmware's: the guard's signal blocked while the bench's function runs; the step is left as it
 * returns once a stop was asked. */
#define HAL_CALL(call)                                       \
    bt_guard *g = current;                                   \
    sigset_t set, old;                                       \
    sigemptyset(&set);                                       \
    sigaddset(&set, guard_signal);                           \
    pthread_sigmask(SIG_BLOCK, &set, &old);                  \
    if (g) atomic_store(&g->in_hal, 1);                      \
    call;                                                    \
    if (g) atomic_store(&g->in_hal, 0);                      \
    pthread_sigmask(SIG_SETMASK, &old, NULL);                \
    if (g && atomic_load(&g->stop)) siglongjmp(*leave, 1)

static void w_spi_sequence(void *ctx, const bt_word *words, uint16_t *miso, size_t n) {
    const bt_hal *h = ctx;
    HAL_CALL(h->spi_sequence(h->ctx, words, miso, n));
}
static void w_spi_bytes(void *ctx, uint8_t cs, uint8_t keep_cs, const uint8_t *tx, uint8_t *rx, size_t n) {
    const bt_hal *h = ctx;
    HAL_CALL(h->spi_bytes(h->ctx, cs, keep_cs, tx, rx, n));
}
static void w_delay_us(void *ctx, uint32_t us) {
    const bt_hal *h = ctx;
    HAL_CALL(h->delay_us(h->ctx, us));
}
static uint64_t w_micros(void *ctx) {
    const bt_hal *h = ctx;
    uint64_t r;
    HAL_CALL(r = h->micros(h->ctx));
    return r;
}
static void w_uart_write(void *ctx, const uint8_t *data, size_t n) {
    const bt_hal *h = ctx;
    HAL_CALL(h->uart_write(h->ctx, data, n));
}
static size_t w_uart_read(void *ctx, uint8_t *buf, size_t max) {
    const bt_hal *h = ctx;
    size_t r;
    HAL_CALL(r = h->uart_read(h->ctx, buf, max));
    return r;
}

/* Fill *wrapper with the HAL the firmware is given: each function blocks the guard signal around real's. */
void bt_guard_wrap(const bt_hal *real, bt_hal *wrapper) {
    wrapper->ctx = (void *)real;
    wrapper->spi_sequence = w_spi_sequence;
    wrapper->spi_bytes = w_spi_bytes;
    wrapper->delay_us = w_delay_us;
    wrapper->micros = w_micros;
    wrapper->uart_write = w_uart_write;
    wrapper->uart_read = w_uart_read;
}
