/* Stopping a firmware's bt_step that hangs (bench/hosts/cosim.py): a bench thread runs bt_step through
 * bt_guard_step, and a watchdog that gives up on it sends that thread BT_GUARD_SIGNAL; the handler jumps back out
 * of the firmware's loop and bt_guard_step returns 1, so the thread ends instead of spinning a core until the
 * process exits.  The firmware is given a HAL of wrappers (bt_guard_wrap) that block the signal while the bench's
 * HAL function (Python) runs: the jump only ever leaves firmware code, never the interpreter; a signal that comes
 * during a HAL call acts as it returns.  The firmware's state after a jump is not to be used again. */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <signal.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "bt_hal.h"

static _Thread_local sigjmp_buf *inside; /* set while this thread runs bt_step through bt_guard_step */
static int guard_signal;

static void on_signal(int sig) {
    (void)sig;
    if (inside) siglongjmp(*inside, 1);
}

/* Install the handler for signal sig (a real-time signal nothing else uses); 0 on success. */
int bt_guard_install(int sig) {
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    guard_signal = sig;
    return sigaction(sig, &sa, NULL);
}

/* Run step(state); 0 when it returned, 1 when the guard signal stopped it. */
int bt_guard_step(void (*step)(void *), void *state) {
    sigjmp_buf env;
    if (sigsetjmp(env, 1)) {
        inside = NULL;
        return 1;
    }
    inside = &env;
    step(state);
    inside = NULL;
    return 0;
}

#define BLOCKED(call)                                        \
    sigset_t set, old;                                       \
    sigemptyset(&set);                                       \
    sigaddset(&set, guard_signal);                           \
    pthread_sigmask(SIG_BLOCK, &set, &old);                  \
    call;                                                    \
    pthread_sigmask(SIG_SETMASK, &old, NULL)

static void w_spi_sequence(void *ctx, const bt_word *words, uint16_t *miso, size_t n) {
    const bt_hal *h = ctx;
    BLOCKED(h->spi_sequence(h->ctx, words, miso, n));
}
static void w_spi_bytes(void *ctx, uint8_t cs, uint8_t keep_cs, const uint8_t *tx, uint8_t *rx, size_t n) {
    const bt_hal *h = ctx;
    BLOCKED(h->spi_bytes(h->ctx, cs, keep_cs, tx, rx, n));
}
static void w_delay_us(void *ctx, uint32_t us) {
    const bt_hal *h = ctx;
    BLOCKED(h->delay_us(h->ctx, us));
}
static uint64_t w_micros(void *ctx) {
    const bt_hal *h = ctx;
    uint64_t r;
    BLOCKED(r = h->micros(h->ctx));
    return r;
}
static void w_uart_write(void *ctx, const uint8_t *data, size_t n) {
    const bt_hal *h = ctx;
    BLOCKED(h->uart_write(h->ctx, data, n));
}
static size_t w_uart_read(void *ctx, uint8_t *buf, size_t max) {
    const bt_hal *h = ctx;
    size_t r;
    BLOCKED(r = h->uart_read(h->ctx, buf, max));
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
