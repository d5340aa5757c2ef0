/* A request to stop (SIGINT from Ctrl-C, SIGTERM from kill or a batch
 * system's time limit), caught by the program that asks for it
 * (airlaunch_catch_interrupts, called by airlaunch_main only) and polled by
 * the integrators between their steps (airlaunch_interrupt_signal), which then
 * end the run as interrupted: its output so far is written and the program
 * exits 128 + the signal.  The handler only records the signal and puts both
 * signals back to their default action (async-signal safe), so a second one,
 * of either kind, ends the process at once.  A process that never calls airlaunch_catch_interrupts (the sweep,
 * the tests) keeps the default actions: the poll always gives 0. */
#define _GNU_SOURCE
#include <signal.h>
#include <string.h>

static volatile sig_atomic_t airlaunch_caught = 0;

/* The first SIGINT or SIGTERM: recorded, and both signals back to their
 * default action, so that a second one of either kind ends the process
 * (sigaction is async-signal safe). */
static void airlaunch_on_signal(int signo) {
  struct sigaction dfl;
  memset(&dfl, 0, sizeof dfl);
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  sigaction(SIGINT, &dfl, NULL);
  sigaction(SIGTERM, &dfl, NULL);
  airlaunch_caught = signo;
}

void airlaunch_catch_interrupts(void) {
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = airlaunch_on_signal;
  sigemptyset(&sa.sa_mask);
  sigaddset(&sa.sa_mask, SIGINT);    /* (no second handler while the first runs) */
  sigaddset(&sa.sa_mask, SIGTERM);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, NULL);
  sigaction(SIGTERM, &sa, NULL);
}

/* The signal caught so far (0: none). */
int airlaunch_interrupt_signal(void) { return (int)airlaunch_caught; }

/* SIGINT's and SIGTERM's numbers, for messages and exit statuses. */
int airlaunch_sigint(void) { return SIGINT; }
int airlaunch_sigterm(void) { return SIGTERM; }
