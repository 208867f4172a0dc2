// Communicator: the ranks that run one level (DESIGN.md 5). Without MPI (or with a communicator
// of one rank) every operation is the identity and costs nothing.
//
// Reductions that feed the simulation (sums of energies, wall loads, outlet masses) must give the
// same bits on every rank, or ranks could take different branches (a servo wall moved
// differently, a rebuild on one rank only) and hang in the next collective. MPI_Allreduce does not
// promise that, so sums gather every rank's values and add them in rank order on every rank.
// Max and min are exact in any order and use MPI_Allreduce; NaN is mapped to +inf first so that
// every rank sees it.
//
// The communicator is duplicated at construction so that the level's messages never meet the
// user's on the same communicator.
#pragma once

#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace grainscale {

// A global id carried bit for bit in a Real slot of a record (and back).
inline Real id_bits(GlobalId id) {
  Real r;
  std::memcpy(&r, &id, sizeof r);
  return r;
}
inline GlobalId bits_id(Real r) {
  GlobalId id;
  std::memcpy(&id, &r, sizeof id);
  return id;
}

// Messages in flight (Communicator::start_sendrecv); finished by Communicator::wait.
class Requests {
 public:
  Requests();
  ~Requests();
  Requests(const Requests&) = delete;
  Requests& operator=(const Requests&) = delete;
  Requests(Requests&&) noexcept;
  Requests& operator=(Requests&&) noexcept;

 private:
  friend class Communicator;
  struct List;
  std::unique_ptr<List> list_;
};

class Communicator {
 public:
  Communicator() = default;  // one rank
  // From an MPI communicator handle in Fortran form (mpi4py: comm.py2f()); MPI must be
  // initialised. Throws InvalidArgument in a build without MPI.
  static Communicator from_fortran_handle(std::int64_t handle);
  static bool mpi_available();

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool parallel() const { return size_ > 1; }

  Real sum(Real v) const;
  std::int64_t sum(std::int64_t v) const;
  // Element-wise sum of equally long vectors, added in rank order.
  void sum_in_place(std::vector<Real>& v) const;
  void sum_in_place(std::vector<std::int64_t>& v) const;
  Real max(Real v) const;
  Real min(Real v) const;
  // Element-wise extremes (exact in any order; NaN counts as the extreme).
  void max_in_place(std::vector<Real>& v) const;
  void min_in_place(std::vector<Real>& v) const;
  std::int64_t max(std::int64_t v) const;
  bool any(bool v) const { return max(static_cast<std::int64_t>(v)) != 0; }
  bool all(bool v) const { return !any(!v); }

  // Concatenation of every rank's bytes in rank order (on every rank); `counts` gets the sizes.
  std::vector<char> allgather(const std::vector<char>& mine, std::vector<int>* counts) const;
  // The same for values (rows of records packed as Real; ids travel as their bits: id_bits,
  // bits_id).
  std::vector<Real> allgather(const std::vector<Real>& mine) const;
  // Personalised exchange: send[r] goes to rank r; returns what every rank sent here, in rank
  // order.
  std::vector<char> alltoall(const std::vector<std::vector<char>>& send) const;
  // Sends `send` to rank `dest` and receives from rank `source` (either may be -1: none);
  // the received size need not be known. Returns the received bytes.
  std::vector<char> sendrecv(const std::vector<char>& send, int dest, int source, int tag) const;
  // The same with sizes known on both sides (the per-step ghost updates).
  void sendrecv_known(const void* send, std::size_t send_bytes, int dest, void* recv,
                      std::size_t recv_bytes, int source, int tag) const;
  // The same without waiting: the messages travel while the caller works; the buffers must
  // stay untouched until wait(requests) returns. To or from the rank itself it copies at once.
  void start_sendrecv(const void* send, std::size_t send_bytes, int dest, void* recv,
                      std::size_t recv_bytes, int source, int tag, Requests& requests) const;
  void wait(Requests& requests) const;
  void broadcast(std::string& text, int root) const;

  // Collective error agreement: if any rank passes a non-empty message, every rank throws the
  // exception of the lowest such rank (InvalidArgument when `invalid` was set there, else
  // std::runtime_error), naming that rank. A no-op on one rank with an empty message.
  void raise_if_any(const std::string& message, bool invalid = false) const;

 private:
  struct Handle;
  std::shared_ptr<Handle> handle_;
  int rank_ = 0;
  int size_ = 1;
};

}  // namespace grainscale
