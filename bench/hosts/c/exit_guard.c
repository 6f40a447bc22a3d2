/* Linked into every firmware the bench builds (bench/hosts/cosim.py build_firmware, with
 * -Wl,--wrap=exit,--wrap=_exit,--wrap=abort,--wrap=__assert_fail): the firmware's calls that would end the process
 * (exit, _exit, abort, a failed assert) go to the bench's hook instead, which leaves the firmware's step (the step
 * guard's bt_guard_exit, bench/hosts/c/step_guard.c) and says what was called.  Outside a guarded step (in bt_init,
 * or with no hook set) the call does what it always did. */
#include <stdio.h>
#include <stdlib.h>

/* Set by the bench: called with the exit status (-1 for abort and a failed assert) and what was called; returns
 * only when no guarded step runs. */
void (*bt_exit_hook)(int status, const char *what);

_Noreturn void __real_exit(int status);
_Noreturn void __real__exit(int status);
_Noreturn void __real_abort(void);
_Noreturn void __real___assert_fail(const char *assertion, const char *file, unsigned int line, const char *function);
_Noreturn void __wrap_exit(int status);
_Noreturn void __wrap__exit(int status);
_Noreturn void __wrap_abort(void);
_Noreturn void __wrap___assert_fail(const char *assertion, const char *file, unsigned int line, const char *function);

_Noreturn void __wrap_exit(int status) {
    char what[32];
    snprintf(what, sizeof what, "exit(%d)", status);
    if (bt_exit_hook) bt_exit_hook(status, what);
    __real_exit(status);
}

_Noreturn void __wrap__exit(int status) {
    char what[32];
    snprintf(what, sizeof what, "_exit(%d)", status);
    if (bt_exit_hook) bt_exit_hook(status, what);
    __real__exit(status);
}

_Noreturn void __wrap_abort(void) {
    if (bt_exit_hook) bt_exit_hook(-1, "abort()");
    __real_abort();
}

_Noreturn void __wrap___assert_fail(const char *assertion, const char *file, unsigned int line, const char *function) {
    char what[256];
    snprintf(what, sizeof what, "assert(%s), which failed at %s:%u in %s()", assertion, file, line, function);
    if (bt_exit_hook) bt_exit_hook(-1, what);
    __real___assert_fail(assertion, file, line, function);
}
