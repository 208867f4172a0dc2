// Watchdog: a rank that stops answering ends the job with a clear message after a timeout,
// instead of leaving the other ranks waiting for ever in a collective (issue 25).
//
// Every blocking MPI call of the core (and of the Python package, through
// grainscale.parallel.waiting) runs inside a WaitScope. A background thread, started with the
// first parallel communicator, looks twice a second whether the current scope has waited longer
// than the timeout; if so it writes what was awaited, where and for how long to stderr and calls
// MPI_Abort on MPI_COMM_WORLD, which ends every rank of the job. A rank cannot recover from a
// lost partner (its collectives are half done), so an abort, not an exception, is the answer.
//
// The timeout is GRAINSCALE_MPI_TIMEOUT (seconds; 0 switches the watchdog off) when set, else
// 600 s, and can be changed at run time (set_timeout). The job ends with exit code 70. Outside a
// scope nothing is watched, so long computation or output on one rank never trips it; only a wait
// for other ranks does.
#pragma once

namespace grainscale::watchdog {

// Seconds a rank may wait for the others in one call; <= 0 disables the watchdog. Throws
// InvalidArgument for a non-finite value.
void set_timeout(double seconds);
double timeout();

// Starts the watching thread (once per process; later calls do nothing). Called from the
// thread that initialised MPI when a parallel communicator is made; a no-op without MPI.
void start();

// Marks a blocking wait for other ranks; `what` must outlive the scope (a string literal).
// Nested scopes keep the outermost start and label.
class WaitScope {
 public:
  explicit WaitScope(const char* what);
  ~WaitScope();
  WaitScope(const WaitScope&) = delete;
  WaitScope& operator=(const WaitScope&) = delete;
};

}  // namespace grainscale::watchdog
