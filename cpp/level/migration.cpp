#include "level/migration.hpp"

#include <cstring>
#include <stdexcept>

namespace grainscale {

namespace {

// Header of a record: x, v, w, f, tau (15), r, m, 1/m, 1/I, 1/(I + m r^2) (5), id, material,
// pair entries, wall entries (4; bit copies of integers). Then the entries: key + stride values.
constexpr int kHeader = 24;

template <class T>
Real bits(T v) {
  static_assert(sizeof(T) == sizeof(Real));
  Real r;
  std::memcpy(&r, &v, sizeof r);
  return r;
}

template <class T>
T from_bits(Real r) {
  T v;
  std::memcpy(&v, &r, sizeof v);
  return v;
}

void append_entries(std::vector<Real>& out, const HistoryCarry& carry, Index row, int stride) {
  const Index n = carry.row_size(row);
  if (n == 0) return;
  const GlobalId* keys = carry.row_keys(row);
  const Real* values = carry.row_values(row);
  for (Index k = 0; k < n; ++k) {
    out.push_back(bits(keys[k]));
    out.insert(out.end(), values + static_cast<std::size_t>(k) * stride,
               values + static_cast<std::size_t>(k + 1) * stride);
  }
}

void pack(const ParticleStore& ps, Index i, Index row, const HistoryCarry& pairs,
          const HistoryCarry& walls, int stride, std::vector<Real>& out) {
  for (const SharedArray<Vec3>* a :
       {&ps.position, &ps.velocity, &ps.angular_velocity, &ps.force, &ps.torque})
    for (int c = 0; c < 3; ++c) out.push_back((*a)[i][c]);
  out.insert(out.end(), {ps.radius[i], ps.mass[i], ps.inv_mass[i], ps.inv_inertia[i],
                         ps.inv_rolling_inertia[i]});
  out.push_back(bits(ps.id[i]));
  out.push_back(bits(static_cast<std::int64_t>(ps.material[i])));
  out.push_back(bits(static_cast<std::int64_t>(pairs.row_size(row))));
  out.push_back(bits(static_cast<std::int64_t>(walls.row_size(row))));
  append_entries(out, pairs, row, stride);
  append_entries(out, walls, row, stride);
}

// Copies `n` entries starting at `in` into `keys` / `values`; returns the end of them.
const Real* read_entries(const Real* in, std::int64_t n, int stride, std::vector<GlobalId>& keys,
                         std::vector<Real>& values) {
  keys.clear();
  values.clear();
  for (std::int64_t k = 0; k < n; ++k) {
    keys.push_back(from_bits<GlobalId>(*in++));
    values.insert(values.end(), in, in + stride);
    in += stride;
  }
  return in;
}

}  // namespace

MigrationCounts migrate(ParticleStore& ps, std::vector<Index>& origin, HistoryCarry& pair_carry,
                        HistoryCarry& wall_carry, const Domain& domain,
                        const Decomposition& decomposition, const Communicator& comm) {
  MigrationCounts counts;
  const int stride = std::max(pair_carry.stride(), wall_carry.stride());
  const int stride_all = static_cast<int>(comm.max(static_cast<std::int64_t>(stride)));
  const Index n = ps.n_owned();
  std::vector<std::vector<Real>> outgoing(comm.size());
  std::vector<Index> stay;
  stay.reserve(n);
  for (Index i = 0; i < n; ++i) {
    const int dest = decomposition.owner(ps.position[i], domain);
    if (dest == comm.rank()) {
      stay.push_back(i);
      continue;
    }
    pack(ps, i, origin[i], pair_carry, wall_carry, stride_all, outgoing[dest]);
    ++counts.sent;
  }
  std::vector<std::vector<char>> send(comm.size());
  for (int r = 0; r < comm.size(); ++r) {
    send[r].resize(outgoing[r].size() * sizeof(Real));
    if (!send[r].empty()) std::memcpy(send[r].data(), outgoing[r].data(), send[r].size());
  }
  const std::vector<char> bytes = comm.alltoall(send);
  std::vector<Real> incoming(bytes.size() / sizeof(Real));
  if (!bytes.empty()) std::memcpy(incoming.data(), bytes.data(), bytes.size());

  // The carries of the new owned set: the stayers' rows in their new order, then the arrivals.
  HistoryCarry pairs, walls;
  pairs.start(stride_all);
  walls.start(stride_all);
  for (Index k = 0; k < static_cast<Index>(stay.size()); ++k) {
    const Index row = origin[stay[k]];
    const Index np = pair_carry.row_size(row), nw = wall_carry.row_size(row);
    pairs.append_row(np ? pair_carry.row_keys(row) : nullptr,
                     np ? pair_carry.row_values(row) : nullptr, np);
    walls.append_row(nw ? wall_carry.row_keys(row) : nullptr,
                     nw ? wall_carry.row_values(row) : nullptr, nw);
  }
  if (counts.sent > 0) ps.select_owned(stay);

  std::vector<GlobalId> keys;
  std::vector<Real> values;
  const Real* p = incoming.data();
  const Real* end = p + incoming.size();
  while (p < end) {
    if (end - p < kHeader) throw std::runtime_error("migration: truncated particle record");
    const Vec3 x(p[0], p[1], p[2]), v(p[3], p[4], p[5]), w(p[6], p[7], p[8]);
    const Vec3 f(p[9], p[10], p[11]), t(p[12], p[13], p[14]);
    const Real r = p[15], m = p[16], im = p[17], ii = p[18], irl = p[19];
    const GlobalId id = from_bits<GlobalId>(p[20]);
    const auto mat = static_cast<std::int32_t>(from_bits<std::int64_t>(p[21]));
    const std::int64_t np = from_bits<std::int64_t>(p[22]), nw = from_bits<std::int64_t>(p[23]);
    p += kHeader;
    ps.add_owned(id, x, v, w, r, m, 1 / ii, mat);
    const Index i = ps.n_owned() - 1;
    // The sender's exact reciprocals, not ones recomputed here.
    ps.inv_mass[i] = im;
    ps.inv_inertia[i] = ii;
    ps.inv_rolling_inertia[i] = irl;
    ps.force[i] = f;
    ps.torque[i] = t;
    p = read_entries(p, np, stride_all, keys, values);
    pairs.append_row(keys.data(), values.data(), static_cast<Index>(np));
    p = read_entries(p, nw, stride_all, keys, values);
    walls.append_row(keys.data(), values.data(), static_cast<Index>(nw));
    ++counts.received;
  }
  pair_carry = std::move(pairs);
  wall_carry = std::move(walls);
  origin.resize(ps.n_owned());
  for (Index i = 0; i < ps.n_owned(); ++i) origin[i] = i;
  return counts;
}

}  // namespace grainscale
