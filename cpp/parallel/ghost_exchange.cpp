#include "parallel/ghost_exchange.hpp"

#include <cmath>
#include <cstring>

namespace grainscale {

void wrap_periodic(ParticleStore& ps, const Domain& domain) {
  const Vec3 L = domain.length();
  for (int a = 0; a < 3; ++a) {
    if (!domain.periodic[a]) continue;
    for (Index i = 0; i < ps.n_owned(); ++i) {
      Real& x = ps.position[i][a];
      if (x < domain.lo[a] || x >= domain.hi[a]) {
        x -= L[a] * std::floor((x - domain.lo[a]) / L[a]);
        if (x >= domain.hi[a]) x = domain.lo[a];  // round-off at the upper face
      }
    }
  }
}

namespace {

// Build records: x, v, w, r, m, 1/m, 1/I, 1/(I + m r^2), id and material (bit copies).
constexpr int kBuildWidth = 16;
// Forward: x, v, w. Reverse: f, tau.
constexpr int kForwardWidth = 9;
constexpr int kReverseWidth = 6;

int tag_of(const GhostStage& s, int kind) { return 1000 + 10 * kind + 2 * s.axis + (s.dir > 0); }

bool self_stage(const GhostStage& s, const Communicator& comm) {
  return s.send_to == comm.rank() && s.recv_from == comm.rank();
}

void pack_build(const ParticleStore& ps, Index i, const Vec3& shift, Real* out) {
  const Vec3 x = ps.position[i] + shift;
  for (int c = 0; c < 3; ++c) {
    out[c] = x[c];
    out[3 + c] = ps.velocity[i][c];
    out[6 + c] = ps.angular_velocity[i][c];
  }
  out[9] = ps.radius[i];
  out[10] = ps.mass[i];
  out[11] = ps.inv_mass[i];
  out[12] = ps.inv_inertia[i];
  out[13] = ps.inv_rolling_inertia[i];
  const GlobalId id = ps.id[i];
  const std::int64_t mat = ps.material[i];
  std::memcpy(&out[14], &id, sizeof(Real));
  std::memcpy(&out[15], &mat, sizeof(Real));
}

void unpack_build(ParticleStore& ps, Index g, const Real* in) {
  ps.position[g] = Vec3(in[0], in[1], in[2]);
  ps.velocity[g] = Vec3(in[3], in[4], in[5]);
  ps.angular_velocity[g] = Vec3(in[6], in[7], in[8]);
  ps.force[g].setZero();
  ps.torque[g].setZero();
  ps.radius[g] = in[9];
  ps.mass[g] = in[10];
  ps.inv_mass[g] = in[11];
  ps.inv_inertia[g] = in[12];
  ps.inv_rolling_inertia[g] = in[13];
  GlobalId id;
  std::int64_t mat;
  std::memcpy(&id, &in[14], sizeof(Real));
  std::memcpy(&mat, &in[15], sizeof(Real));
  ps.id[g] = id;
  ps.material[g] = static_cast<std::int32_t>(mat);
}

}  // namespace

void GhostExchange::build(ParticleStore& ps, const Domain& domain,
                          const Decomposition& decomposition, const Communicator& comm,
                          Real cutoff) {
  ps.clear_ghosts();
  stages_.clear();
  const Vec3 L = domain.length();
  for (int a = 0; a < 3; ++a) {
    if (decomposition.grid[a] == 1 && !domain.periodic[a]) continue;
    const Index candidates = ps.n_local();  // owned + ghosts of the earlier axes
    const Real lo = decomposition.lo(a), hi = decomposition.hi(a);
    for (int dir : {-1, +1}) {
      GhostStage s;
      s.axis = a;
      s.dir = dir;
      s.send_to = decomposition.neighbor(a, dir, domain);
      s.recv_from = decomposition.neighbor(a, -dir, domain);
      // Sent across the periodic boundary: the receiver sees the images one box length away.
      const int c = decomposition.coords[a];
      if (dir < 0 && c == 0 && domain.periodic[a]) s.shift[a] = L[a];
      if (dir > 0 && c == decomposition.grid[a] - 1 && domain.periodic[a]) s.shift[a] = -L[a];
      if (s.send_to >= 0)
        for (Index i = 0; i < candidates; ++i) {
          const Real x = ps.position[i][a];
          if (dir < 0 ? x < lo + cutoff : x > hi - cutoff) s.send.push_back(i);
        }
      const std::size_t n_send = s.send.size();
      if (self_stage(s, comm)) {
        s.recv_first = ps.add_ghost_slots(static_cast<Index>(n_send));
        s.recv_count = static_cast<Index>(n_send);
        std::vector<Real> rec(kBuildWidth);
        for (std::size_t k = 0; k < n_send; ++k) {
          pack_build(ps, s.send[k], s.shift, rec.data());
          unpack_build(ps, s.recv_first + static_cast<Index>(k), rec.data());
        }
      } else {
        std::vector<char> out(n_send * kBuildWidth * sizeof(Real));
        Real* p = reinterpret_cast<Real*>(out.data());
        for (std::size_t k = 0; k < n_send; ++k)
          pack_build(ps, s.send[k], s.shift, p + k * kBuildWidth);
        const std::vector<char> in = comm.sendrecv(out, s.send_to, s.recv_from, tag_of(s, 0));
        const Index n_recv = static_cast<Index>(in.size() / (kBuildWidth * sizeof(Real)));
        s.recv_first = ps.add_ghost_slots(n_recv);
        s.recv_count = n_recv;
        const Real* q = reinterpret_cast<const Real*>(in.data());
        for (Index k = 0; k < n_recv; ++k) unpack_build(ps, s.recv_first + k, q + k * kBuildWidth);
      }
      stages_.push_back(std::move(s));
    }
  }
  find_deferred(ps.n_owned(), comm);
}

void GhostExchange::forward(ParticleStore& ps, const Communicator& comm) {
  Vec3* x = ps.position.data();
  Vec3* v = ps.velocity.data();
  Vec3* w = ps.angular_velocity.data();
  for (const GhostStage& s : stages_) {
    const std::size_t n_send = s.send.size();
    if (self_stage(s, comm)) {
      for (std::size_t k = 0; k < n_send; ++k) {
        const Index i = s.send[k], g = s.recv_first + static_cast<Index>(k);
        x[g] = x[i] + s.shift;
        v[g] = v[i];
        w[g] = w[i];
      }
      continue;
    }
    send_buffer_.resize(n_send * kForwardWidth);
    recv_buffer_.resize(static_cast<std::size_t>(s.recv_count) * kForwardWidth);
    Real* p = send_buffer_.data();
    for (std::size_t k = 0; k < n_send; ++k, p += kForwardWidth) {
      const Index i = s.send[k];
      const Vec3 xs = x[i] + s.shift;
      for (int c = 0; c < 3; ++c) {
        p[c] = xs[c];
        p[3 + c] = v[i][c];
        p[6 + c] = w[i][c];
      }
    }
    comm.sendrecv_known(send_buffer_.data(), send_buffer_.size() * sizeof(Real), s.send_to,
                        recv_buffer_.data(), recv_buffer_.size() * sizeof(Real), s.recv_from,
                        tag_of(s, 1));
    const Real* q = recv_buffer_.data();
    for (Index k = 0; k < s.recv_count; ++k, q += kForwardWidth) {
      const Index g = s.recv_first + k;
      x[g] = Vec3(q[0], q[1], q[2]);
      v[g] = Vec3(q[3], q[4], q[5]);
      w[g] = Vec3(q[6], q[7], q[8]);
    }
  }
}

void GhostExchange::set_stages(std::vector<GhostStage> stages, Index n_owned,
                               const Communicator& comm) {
  stages_ = std::move(stages);
  find_deferred(n_owned, comm);
}

void GhostExchange::find_deferred(Index n_owned, const Communicator& comm) {
  // The last axis with a stage to or from another rank starts the asynchronous part; without
  // one, reverse_begin does everything (copies on this rank), in the order of `reverse`.
  split_ = 0;
  bool remote = false;
  for (std::size_t k = stages_.size(); k-- > 0;) {
    const GhostStage& s = stages_[k];
    if (!self_stage(s, comm) && (s.send_to >= 0 || s.recv_from >= 0)) {
      split_ = k;
      while (split_ > 0 && stages_[split_ - 1].axis == s.axis) --split_;
      remote = true;
      break;
    }
  }
  deferred_.clear();
  deferred_mask_.assign(static_cast<std::size_t>(n_owned), 0);
  if (!remote) return;
  // Any owned particle that was sent may get forces back, directly or through the ghosts of
  // later stages that mirror it.
  for (const GhostStage& s : stages_)
    for (Index i : s.send)
      if (i < n_owned) deferred_mask_[i] = 1;
  for (Index i = 0; i < n_owned; ++i)
    if (deferred_mask_[i]) deferred_.push_back(i);
}

namespace {

void add_back_local(const GhostStage& s, Vec3* f, Vec3* t) {
  for (std::size_t k = 0; k < s.send.size(); ++k) {
    const Index i = s.send[k], g = s.recv_first + static_cast<Index>(k);
    f[i] += f[g];
    t[i] += t[g];
  }
}

void pack_reverse(const GhostStage& s, const Vec3* f, const Vec3* t, std::vector<Real>& out) {
  out.resize(static_cast<std::size_t>(s.recv_count) * kReverseWidth);
  Real* p = out.data();
  for (Index k = 0; k < s.recv_count; ++k, p += kReverseWidth) {
    const Index g = s.recv_first + k;
    for (int c = 0; c < 3; ++c) {
      p[c] = f[g][c];
      p[3 + c] = t[g][c];
    }
  }
}

void add_back_received(const GhostStage& s, const std::vector<Real>& in, Vec3* f, Vec3* t) {
  const Real* q = in.data();
  for (std::size_t k = 0; k < s.send.size(); ++k, q += kReverseWidth) {
    const Index i = s.send[k];
    f[i] += Vec3(q[0], q[1], q[2]);
    t[i] += Vec3(q[3], q[4], q[5]);
  }
}

}  // namespace

void GhostExchange::reverse_begin(ParticleStore& ps, const Communicator& comm) {
  Vec3* f = ps.force.data();
  Vec3* t = ps.torque.data();
  in_flight_.clear();
  // The stages after the split axis copy on this rank (find_deferred chose the split so).
  for (std::size_t k = stages_.size(); k-- > split_;) {
    const GhostStage& s = stages_[k];
    if (self_stage(s, comm)) {
      add_back_local(s, f, t);
      continue;
    }
    in_flight_.push_back(k);
  }
  async_send_.resize(in_flight_.size());
  async_recv_.resize(in_flight_.size());
  // Both stages of the split axis are packed before either adds anything: a stage forwards only
  // what its axis started with, so neither's ghosts receive from the other, as in `reverse`.
  for (std::size_t j = 0; j < in_flight_.size(); ++j) {
    const GhostStage& s = stages_[in_flight_[j]];
    pack_reverse(s, f, t, async_send_[j]);
    async_recv_[j].resize(s.send.size() * kReverseWidth);
    comm.start_sendrecv(async_send_[j].data(), async_send_[j].size() * sizeof(Real), s.recv_from,
                        async_recv_[j].data(), async_recv_[j].size() * sizeof(Real), s.send_to,
                        tag_of(s, 2), requests_);
  }
}

void GhostExchange::reverse_end(ParticleStore& ps, const Communicator& comm) {
  Vec3* f = ps.force.data();
  Vec3* t = ps.torque.data();
  comm.wait(requests_);
  for (std::size_t j = 0; j < in_flight_.size(); ++j)
    add_back_received(stages_[in_flight_[j]], async_recv_[j], f, t);
  in_flight_.clear();
  for (std::size_t k = split_; k-- > 0;) {
    const GhostStage& s = stages_[k];
    if (self_stage(s, comm)) {
      add_back_local(s, f, t);
      continue;
    }
    // The ghosts go back where they came from; the forces on what this rank sent come in.
    pack_reverse(s, f, t, send_buffer_);
    recv_buffer_.resize(s.send.size() * kReverseWidth);
    comm.sendrecv_known(send_buffer_.data(), send_buffer_.size() * sizeof(Real), s.recv_from,
                        recv_buffer_.data(), recv_buffer_.size() * sizeof(Real), s.send_to,
                        tag_of(s, 2));
    add_back_received(s, recv_buffer_, f, t);
  }
}

}  // namespace grainscale
