// GhostExchange: the ghost particles of one rank — periodic images and halo copies from the
// neighbouring ranks, made by one mechanism (DESIGN.md 2.1, 5).
//
// Ghosts are built in stages, axis by axis (x, y, z) and per axis towards the lower then the
// upper neighbour: a stage sends the particles present when its axis began (owned ones and the
// ghosts of earlier axes) that lie within `cutoff` of the subdomain's lower (upper) face, and
// receives the matching ones from the opposite neighbour as new ghosts. Corners and edges are
// covered because later axes forward the ghosts of earlier ones (the scheme of LAMMPS'
// `comm brick`). Crossing a periodic boundary adds the box length to the positions sent; a stage
// whose neighbour is the rank itself (one rank along a periodic axis) copies locally, which is
// the serial run's periodic images. One hop per axis suffices because every slab is at least
// `cutoff` wide (checked by the level).
//
//   build   – creates the ghosts (full particle data) after the owned particles were migrated;
//   forward – every step: positions (plus shift), velocities and spins into the ghost slots;
//   reverse – (reverse_begin, then reverse_end) stages in reverse order: ghost forces and
//             torques added to the particles they mirror (which may be ghosts of an earlier
//             stage, passed on in their own stage).
// Pairs are stored once (neighbor_list.hpp), so Newton's third law holds across ranks: a pair
// between ranks is computed on the rank owning its particle with the smaller global id and the
// partner's share travels back in the reverse pass.
//
// The reverse pass is split so that the forces travel while the rank works: reverse_begin does
// the stages of the axes after the last one with another rank (copies on the rank itself) and
// starts that axis's messages; reverse_end waits for them and does the stages before it. In
// between only the owned particles that
// were sent as ghosts (`deferred()`, whose forces are still incomplete) must not be used: the
// level integrates the others first. Why: with one synchronisation per phase each rank waits
// for the other in whichever phase it is faster (bench/SCALING.md section 4).
#pragma once

#include <cstdint>
#include <vector>

#include "parallel/communicator.hpp"
#include "parallel/decomposition.hpp"
#include "state/domain.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

struct GhostStage {
  int axis = 0;
  int dir = -1;               // -1: towards the lower neighbour, +1: towards the upper one
  int send_to = -1;           // rank (-1: none: closed end)
  int recv_from = -1;         // rank (-1: none)
  Vec3 shift = Vec3::Zero();  // added to the positions sent
  std::vector<Index> send;    // local particles sent
  Index recv_first = 0;       // ghost slots [recv_first, recv_first + recv_count)
  Index recv_count = 0;
};

class GhostExchange {
 public:
  void build(ParticleStore& ps, const Domain& domain, const Decomposition& decomposition,
             const Communicator& comm, Real cutoff);
  void forward(ParticleStore& ps, const Communicator& comm);
  void reverse_begin(ParticleStore& ps, const Communicator& comm);
  void reverse_end(ParticleStore& ps, const Communicator& comm);
  // The owned particles whose forces reverse_end completes (empty without another rank), in
  // increasing order, and the same as a per-owned-particle mask.
  const std::vector<Index>& deferred() const { return deferred_; }
  const std::vector<std::uint8_t>& deferred_mask() const { return deferred_mask_; }
  void clear() {
    stages_.clear();
    split_ = 0;
    deferred_.clear();
    deferred_mask_.clear();
  }

  const std::vector<GhostStage>& stages() const { return stages_; }
  // Checkpoints: the stages of a saved exchange (with the ghost slots restored alongside).
  void set_stages(std::vector<GhostStage> stages, Index n_owned, const Communicator& comm);

 private:
  void find_deferred(Index n_owned, const Communicator& comm);

  std::vector<GhostStage> stages_;
  std::vector<Real> send_buffer_, recv_buffer_;
  // reverse_begin does the stages from split_ on (those of the split axis in flight, with their
  // buffers), reverse_end the ones before it.
  std::size_t split_ = 0;
  std::vector<std::size_t> in_flight_;
  std::vector<std::vector<Real>> async_send_, async_recv_;
  Requests requests_;
  std::vector<Index> deferred_;
  std::vector<std::uint8_t> deferred_mask_;
};

// Wraps owned particles into the box along periodic axes.
void wrap_periodic(ParticleStore& ps, const Domain& domain);

}  // namespace grainscale
