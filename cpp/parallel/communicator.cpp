#include "parallel/communicator.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "core/errors.hpp"
#include "parallel/watchdog.hpp"

#ifdef GRAINSCALE_HAVE_MPI
#include <mpi.h>
#endif

namespace grainscale {

#ifdef GRAINSCALE_HAVE_MPI
struct Communicator::Handle {
  MPI_Comm comm = MPI_COMM_NULL;
  ~Handle() {
    // After MPI_Finalize (interpreter exit with a live simulation) freeing is not allowed.
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized && comm != MPI_COMM_NULL) MPI_Comm_free(&comm);
  }
};
#else
struct Communicator::Handle {};
#endif

#ifdef GRAINSCALE_HAVE_MPI
struct Requests::List {
  std::vector<MPI_Request> pending;
};
#else
struct Requests::List {
  std::vector<int> pending;  // always empty: a serial run has no messages in flight
};
#endif

Requests::Requests() : list_(std::make_unique<List>()) {}
Requests::~Requests() {
#ifdef GRAINSCALE_HAVE_MPI
  // Unfinished requests (an exception between start and wait) are waited for: freeing the
  // buffers under a live request would corrupt memory. Not after MPI_Finalize.
  int finalized = 0;
  MPI_Finalized(&finalized);
  watchdog::WaitScope waiting("a ghost exchange (MPI_Waitall)");
  if (!finalized && list_ && !list_->pending.empty())
    MPI_Waitall(static_cast<int>(list_->pending.size()), list_->pending.data(),
                MPI_STATUSES_IGNORE);
#endif
}
Requests::Requests(Requests&&) noexcept = default;
Requests& Requests::operator=(Requests&&) noexcept = default;

bool Communicator::mpi_available() {
#ifdef GRAINSCALE_HAVE_MPI
  return true;
#else
  return false;
#endif
}

Communicator Communicator::from_fortran_handle(std::int64_t handle) {
#ifdef GRAINSCALE_HAVE_MPI
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized)
    throw InvalidArgument("Simulation.comm needs MPI to be initialised (import mpi4py.MPI first)");
  Communicator c;
  c.handle_ = std::make_shared<Handle>();
  MPI_Comm_dup(MPI_Comm_f2c(static_cast<MPI_Fint>(handle)), &c.handle_->comm);
  MPI_Comm_rank(c.handle_->comm, &c.rank_);
  MPI_Comm_size(c.handle_->comm, &c.size_);
  if (c.size_ > 1) watchdog::start();
  return c;
#else
  (void)handle;
  throw InvalidArgument(
      "Simulation.comm must be None in this build of grainscale (built without MPI), got a "
      "communicator");
#endif
}

Real Communicator::sum(Real v) const {
  if (!parallel()) return v;
  std::vector<Real> a{v};
  sum_in_place(a);
  return a[0];
}

std::int64_t Communicator::sum(std::int64_t v) const {
  if (!parallel()) return v;
  std::vector<std::int64_t> a{v};
  sum_in_place(a);
  return a[0];
}

namespace {
template <class T>
void ordered_sum(const std::vector<char>& all, std::vector<T>& v, int size) {
  const std::size_t n = v.size();
  std::vector<T> part(n);
  std::fill(v.begin(), v.end(), T(0));
  for (int r = 0; r < size; ++r) {
    std::memcpy(part.data(), all.data() + r * n * sizeof(T), n * sizeof(T));
    for (std::size_t k = 0; k < n; ++k) v[k] += part[k];
  }
}
}  // namespace

void Communicator::sum_in_place(std::vector<Real>& v) const {
  if (!parallel() || v.empty()) return;
  std::vector<char> mine(v.size() * sizeof(Real));
  std::memcpy(mine.data(), v.data(), mine.size());
  ordered_sum(allgather(mine, nullptr), v, size_);
}

void Communicator::sum_in_place(std::vector<std::int64_t>& v) const {
  if (!parallel() || v.empty()) return;
  std::vector<char> mine(v.size() * sizeof(std::int64_t));
  std::memcpy(mine.data(), v.data(), mine.size());
  ordered_sum(allgather(mine, nullptr), v, size_);
}

Real Communicator::max(Real v) const {
  if (std::isnan(v)) v = std::numeric_limits<Real>::infinity();
  if (!parallel()) return v;
#ifdef GRAINSCALE_HAVE_MPI
  Real out = v;
  watchdog::WaitScope waiting("a reduction (MPI_Allreduce)");
  MPI_Allreduce(&v, &out, 1, MPI_DOUBLE, MPI_MAX, handle_->comm);
  return out;
#else
  return v;
#endif
}

void Communicator::max_in_place(std::vector<Real>& v) const {
  for (Real& x : v)
    if (std::isnan(x)) x = std::numeric_limits<Real>::infinity();
  if (!parallel() || v.empty()) return;
#ifdef GRAINSCALE_HAVE_MPI
  watchdog::WaitScope waiting("a reduction (MPI_Allreduce)");
  MPI_Allreduce(MPI_IN_PLACE, v.data(), static_cast<int>(v.size()), MPI_DOUBLE, MPI_MAX,
                handle_->comm);
#endif
}

void Communicator::min_in_place(std::vector<Real>& v) const {
  for (Real& x : v) x = std::isnan(x) ? std::numeric_limits<Real>::infinity() : -x;
  max_in_place(v);
  for (Real& x : v) x = -x;
}

Real Communicator::min(Real v) const {
  if (std::isnan(v)) v = -std::numeric_limits<Real>::infinity();
  return -max(-v);
}

std::int64_t Communicator::max(std::int64_t v) const {
  if (!parallel()) return v;
#ifdef GRAINSCALE_HAVE_MPI
  std::int64_t out = v;
  watchdog::WaitScope waiting("a reduction (MPI_Allreduce)");
  MPI_Allreduce(&v, &out, 1, MPI_INT64_T, MPI_MAX, handle_->comm);
  return out;
#else
  return v;
#endif
}

std::vector<char> Communicator::allgather(const std::vector<char>& mine,
                                          std::vector<int>* counts) const {
  if (!parallel()) {
    if (counts) counts->assign(1, static_cast<int>(mine.size()));
    return mine;
  }
#ifdef GRAINSCALE_HAVE_MPI
  watchdog::WaitScope waiting("a gather (MPI_Allgather)");
  int n = static_cast<int>(mine.size());
  std::vector<int> sizes(size_), offsets(size_ + 1, 0);
  MPI_Allgather(&n, 1, MPI_INT, sizes.data(), 1, MPI_INT, handle_->comm);
  for (int r = 0; r < size_; ++r) offsets[r + 1] = offsets[r] + sizes[r];
  std::vector<char> out(offsets[size_]);
  MPI_Allgatherv(mine.data(), n, MPI_BYTE, out.data(), sizes.data(), offsets.data(), MPI_BYTE,
                 handle_->comm);
  if (counts) *counts = sizes;
  return out;
#else
  return mine;
#endif
}

std::vector<Real> Communicator::allgather(const std::vector<Real>& mine) const {
  std::vector<char> bytes(mine.size() * sizeof(Real));
  if (!bytes.empty()) std::memcpy(bytes.data(), mine.data(), bytes.size());
  const std::vector<char> all = allgather(bytes, nullptr);
  std::vector<Real> values(all.size() / sizeof(Real));
  if (!values.empty()) std::memcpy(values.data(), all.data(), all.size());
  return values;
}

std::vector<char> Communicator::alltoall(const std::vector<std::vector<char>>& send) const {
  if (static_cast<int>(send.size()) != size_)
    throw std::logic_error("Communicator::alltoall needs one buffer per rank");
  if (!parallel()) return send[0];
#ifdef GRAINSCALE_HAVE_MPI
  watchdog::WaitScope waiting("an exchange (MPI_Alltoall)");
  std::vector<int> scount(size_), rcount(size_), soff(size_ + 1, 0), roff(size_ + 1, 0);
  for (int r = 0; r < size_; ++r) scount[r] = static_cast<int>(send[r].size());
  MPI_Alltoall(scount.data(), 1, MPI_INT, rcount.data(), 1, MPI_INT, handle_->comm);
  for (int r = 0; r < size_; ++r) {
    soff[r + 1] = soff[r] + scount[r];
    roff[r + 1] = roff[r] + rcount[r];
  }
  std::vector<char> flat(soff[size_]), out(roff[size_]);
  for (int r = 0; r < size_; ++r)
    if (scount[r] > 0) std::memcpy(flat.data() + soff[r], send[r].data(), scount[r]);
  MPI_Alltoallv(flat.data(), scount.data(), soff.data(), MPI_BYTE, out.data(), rcount.data(),
                roff.data(), MPI_BYTE, handle_->comm);
  return out;
#else
  return send[0];
#endif
}

std::vector<char> Communicator::sendrecv(const std::vector<char>& send, int dest, int source,
                                         int tag) const {
#ifdef GRAINSCALE_HAVE_MPI
  if (parallel()) {
    const int to = dest < 0 ? MPI_PROC_NULL : dest, from = source < 0 ? MPI_PROC_NULL : source;
    watchdog::WaitScope waiting("a message exchange (MPI_Sendrecv)");
    std::uint64_t n_send = send.size(), n_recv = 0;
    MPI_Sendrecv(&n_send, 1, MPI_UINT64_T, to, tag, &n_recv, 1, MPI_UINT64_T, from, tag,
                 handle_->comm, MPI_STATUS_IGNORE);
    std::vector<char> out(from == MPI_PROC_NULL ? 0 : n_recv);
    sendrecv_known(send.data(), send.size(), dest, out.data(), out.size(), source, tag);
    return out;
  }
#endif
  (void)tag;
  if (dest == rank_ && source == rank_) return send;
  if (dest < 0 && source < 0) return {};
  throw std::logic_error("Communicator::sendrecv to another rank in a serial run");
}

void Communicator::sendrecv_known(const void* send, std::size_t send_bytes, int dest, void* recv,
                                  std::size_t recv_bytes, int source, int tag) const {
#ifdef GRAINSCALE_HAVE_MPI
  if (parallel()) {
    const int to = dest < 0 ? MPI_PROC_NULL : dest, from = source < 0 ? MPI_PROC_NULL : source;
    // Messages above 2 GiB are split: MPI counts are int.
    watchdog::WaitScope waiting("a message exchange (MPI_Sendrecv)");
    const std::size_t chunk = std::size_t(1) << 30;
    std::size_t s = 0, r = 0;
    const char* sp = static_cast<const char*>(send);
    char* rp = static_cast<char*>(recv);
    do {
      const int ns = static_cast<int>(std::min(chunk, send_bytes - s));
      const int nr = static_cast<int>(std::min(chunk, recv_bytes - r));
      MPI_Sendrecv(sp + s, to == MPI_PROC_NULL ? 0 : ns, MPI_BYTE, to, tag, rp + r,
                   from == MPI_PROC_NULL ? 0 : nr, MPI_BYTE, from, tag, handle_->comm,
                   MPI_STATUS_IGNORE);
      s += ns;
      r += nr;
    } while (s < send_bytes || r < recv_bytes);
    return;
  }
#endif
  (void)tag;
  if (dest == rank_ && source == rank_) {
    if (send_bytes != recv_bytes) throw std::logic_error("sendrecv_known to self: sizes differ");
    if (send_bytes > 0) std::memmove(recv, send, send_bytes);
    return;
  }
  if (dest < 0 && source < 0) return;
  throw std::logic_error("Communicator::sendrecv_known to another rank in a serial run");
}

void Communicator::start_sendrecv(const void* send, std::size_t send_bytes, int dest, void* recv,
                                  std::size_t recv_bytes, int source, int tag,
                                  Requests& requests) const {
#ifdef GRAINSCALE_HAVE_MPI
  if (parallel() && !(dest == rank_ && source == rank_)) {
    // Messages above 1 GiB go in pieces: MPI counts are int.
    const std::size_t chunk = std::size_t(1) << 30;
    if (!requests.list_) requests.list_ = std::make_unique<Requests::List>();  // moved from
    auto& pending = requests.list_->pending;
    if (source >= 0)
      for (std::size_t r = 0; r < recv_bytes || r == 0; r += chunk) {
        pending.emplace_back();
        MPI_Irecv(static_cast<char*>(recv) + r, static_cast<int>(std::min(chunk, recv_bytes - r)),
                  MPI_BYTE, source, tag, handle_->comm, &pending.back());
        if (recv_bytes == 0) break;
      }
    if (dest >= 0)
      for (std::size_t s = 0; s < send_bytes || s == 0; s += chunk) {
        pending.emplace_back();
        MPI_Isend(static_cast<const char*>(send) + s,
                  static_cast<int>(std::min(chunk, send_bytes - s)), MPI_BYTE, dest, tag,
                  handle_->comm, &pending.back());
        if (send_bytes == 0) break;
      }
    return;
  }
#endif
  (void)requests;
  sendrecv_known(send, send_bytes, dest, recv, recv_bytes, source, tag);
}

void Communicator::wait(Requests& requests) const {
#ifdef GRAINSCALE_HAVE_MPI
  if (!requests.list_) return;
  auto& pending = requests.list_->pending;
  watchdog::WaitScope waiting("a ghost exchange (MPI_Waitall)");
  if (!pending.empty())
    MPI_Waitall(static_cast<int>(pending.size()), pending.data(), MPI_STATUSES_IGNORE);
  pending.clear();
#else
  (void)requests;
#endif
}

void Communicator::broadcast(std::string& text, int root) const {
  if (!parallel()) return;
#ifdef GRAINSCALE_HAVE_MPI
  watchdog::WaitScope waiting("a broadcast (MPI_Bcast)");
  std::uint64_t n = text.size();
  MPI_Bcast(&n, 1, MPI_UINT64_T, root, handle_->comm);
  text.resize(n);
  if (n > 0) MPI_Bcast(text.data(), static_cast<int>(n), MPI_CHAR, root, handle_->comm);
#else
  (void)text;
  (void)root;
#endif
}

void Communicator::raise_if_any(const std::string& message, bool invalid) const {
  if (!parallel()) {
    if (message.empty()) return;
    if (invalid) throw InvalidArgument(message);
    throw std::runtime_error(message);
  }
  // Lowest rank with an error; size_ when none.
  const std::int64_t mine = message.empty() ? size_ : rank_;
  const std::int64_t first = -max(-mine);
  if (first == size_) return;
  std::string text = message;
  std::int64_t kind = invalid ? 1 : 0;
  broadcast(text, static_cast<int>(first));
  std::string flag(1, static_cast<char>(kind));
  broadcast(flag, static_cast<int>(first));
  const std::string full = text + " (raised on rank " + std::to_string(first) + ")";
  if (flag[0] == 1) throw InvalidArgument(full);
  throw std::runtime_error(full);
}

}  // namespace grainscale
