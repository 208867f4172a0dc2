#include "parallel/watchdog.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>

#include "core/errors.hpp"

#ifdef GRAINSCALE_HAVE_MPI
#include <mpi.h>
#endif

namespace grainscale::watchdog {
namespace {

double initial_timeout() {
  const char* text = std::getenv("GRAINSCALE_MPI_TIMEOUT");
  if (text == nullptr || *text == '\0') return 600.0;
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(value) || value < 0) {
    std::fprintf(stderr,
                 "grainscale: GRAINSCALE_MPI_TIMEOUT must be a number of seconds, got '%s'; "
                 "using 600\n",
                 text);
    return 600.0;
  }
  return value;
}

using Clock = std::chrono::steady_clock;

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

// The state the scopes write and the thread reads: lock-free, two stores per wait.
std::atomic<double> g_timeout{initial_timeout()};
std::atomic<std::int64_t> g_since{0};  // start of the current wait (ns), 0 when none
std::atomic<const char*> g_what{nullptr};
std::atomic<int> g_depth{0};
std::atomic<int> g_rank{0}, g_size{1};

// The watching thread; stopped and joined at process exit.
class Watcher {
 public:
  Watcher() : thread_([this] { loop(); }) {}
  ~Watcher() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }

 private:
  void loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!wake_.wait_for(lock, std::chrono::milliseconds(500), [this] { return stop_; })) {
      const double limit = g_timeout.load();
      const std::int64_t since = g_since.load();
      if (limit <= 0 || since == 0) continue;
      const double waited = 1e-9 * static_cast<double>(now_ns() - since);
      if (waited > limit) abort_job(waited, limit);
    }
  }

  static void abort_job(double waited, double limit) {
    const char* what = g_what.load();
    std::fprintf(stderr,
                 "grainscale: rank %d of %d has waited %.1f s for the other ranks in %s; one of "
                 "them stopped answering (stuck, killed, or in a different call). Aborting every "
                 "rank (MPI_Abort). The limit is %g s: grainscale.parallel.set_timeout(seconds) "
                 "or GRAINSCALE_MPI_TIMEOUT (0 switches it off).\n",
                 g_rank.load(), g_size.load(), waited, what ? what : "an MPI call", limit);
    std::fflush(stderr);
#ifdef GRAINSCALE_HAVE_MPI
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Abort(MPI_COMM_WORLD, 70);
#endif
    std::abort();  // MPI_Abort returned (it should not) or MPI is gone: end this rank
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace

void set_timeout(double seconds) {
  if (!(std::isfinite(seconds) && seconds >= 0))
    throw InvalidArgument(
        "parallel.set_timeout: seconds must be finite and >= 0 (0 switches the "
        "watchdog off), got " +
        std::to_string(seconds));
  g_timeout.store(seconds);
}

double timeout() { return g_timeout.load(); }

void start() {
#ifdef GRAINSCALE_HAVE_MPI
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) return;
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  g_rank.store(rank);
  g_size.store(size);
  static Watcher watcher;  // constructed once, on the first call
  (void)watcher;
#endif
}

WaitScope::WaitScope(const char* what) {
  if (g_depth.fetch_add(1) == 0) {
    g_what.store(what);
    g_since.store(now_ns());
  }
}

WaitScope::~WaitScope() {
  if (g_depth.fetch_sub(1) == 1) g_since.store(0);
}

}  // namespace grainscale::watchdog
