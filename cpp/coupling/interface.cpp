#include "coupling/interface.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <unordered_set>

#include "coupling/flux_insertion.hpp"

namespace grainscale {

namespace {

// A candidate for removal, gathered from every rank: the same list, in the same order, on all.
struct Candidate {
  int group;  // face (extraction) or cell (shadow removal)
  Real key;   // smaller first within a group
  GlobalId id;
  Real mass;
  Real other;  // a second key (shadow removal: squared distance to the fallback point)
};

// Records of five values: group, key, id (bits), mass, other.
std::vector<Candidate> gather_candidates(const std::vector<Real>& mine, const Communicator& comm) {
  const std::vector<Real> all = comm.allgather(mine);
  std::vector<Candidate> out;
  for (std::size_t k = 0; k + 4 < all.size(); k += 5)
    out.push_back(
        {static_cast<int>(all[k]), all[k + 1], bits_id(all[k + 2]), all[k + 3], all[k + 4]});
  std::sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) {
    return std::tie(a.group, a.key, a.id) < std::tie(b.group, b.key, b.id);
  });
  return out;
}

}  // namespace

Interface::Interface(const InterfaceSpec& spec, const Domain& parent_domain, int dimension)
    : spec_(spec),
      grid_(std::make_shared<const ExchangeGrid>(spec.region, spec.cell_size, parent_domain,
                                                 "Exchange")),
      parent_average_(grid_->grid(), dimension),
      child_average_(grid_->grid(), dimension) {
  const auto& faces = grid_->faces();
  inserters_.reserve(faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f)
    inserters_.emplace_back(faces[f], grid_->grid(), spec.fine_radius, spec.fine_density,
                            spec.fine_material, spec.size_ratio, spec.deadband,
                            spec.seed + 7919 * f);
}

void Interface::start_flux(Level& parent, Real margin) {
  meter_.start(parent.particles(), *grid_, parent.domain(), margin, parent.comm());
}

IntervalFlux Interface::finish_flux(Level& parent) {
  return meter_.finish(parent.particles(), *grid_, parent.domain(), parent.lost_log(),
                       parent.comm());
}

void Interface::book(const IntervalFlux& flux, const std::vector<Vec3>& beyond) {
  const std::size_t n = inserters_.size();
  if (flux.inward.size() != n || flux.outward.size() != n || beyond.size() != n)
    throw std::invalid_argument("Interface.book: one value per interface face expected");
  for (std::size_t f = 0; f < n; ++f) {
    const FaceFlux& in = flux.inward[f];
    FluxInserter& ins = inserters_[f];
    if (in.mass > 0) {
      const Vec3 spin = in.inertia > 0 ? Vec3(in.spin / in.inertia) : Vec3::Zero();
      ins.feed(in.mass, beyond[f], spin);
    } else {
      ins.set_velocity(beyond[f]);
    }
    ins.debit(flux.outward[f].mass);
  }
}

void Interface::credit(const std::vector<Real>& left) {
  if (left.size() != inserters_.size())
    throw std::invalid_argument("Interface.credit: one value per interface face expected");
  for (std::size_t f = 0; f < left.size(); ++f) inserters_[f].credit(left[f]);
}

Real Interface::extract(Level& child) {
  bool any = false;
  for (const FluxInserter& f : inserters_) any = any || f.owing() > 0;
  if (!any) return 0;  // the same on every rank: the ledgers are replicated
  const ParticleStore& ps = child.particles();
  const auto& faces = grid_->faces();
  std::vector<Real> mine;  // face, distance inside the face, id, mass
  for (Index i = 0; i < ps.n_owned(); ++i)
    for (std::size_t f = 0; f < faces.size(); ++f) {
      if (!(inserters_[f].owing() > 0) || !inserters_[f].shell().contains(ps.position[i])) continue;
      const Real s = (ps.position[i] - faces[f].centre).dot(faces[f].normal);
      mine.insert(mine.end(), {static_cast<Real>(f), s, id_bits(ps.id[i]), ps.mass[i], 0.0});
    }
  std::vector<Real> owing(faces.size());  // the whole debt, once out of the dead band
  for (std::size_t f = 0; f < faces.size(); ++f) owing[f] = inserters_[f].owing();
  std::vector<GlobalId> chosen;
  std::unordered_set<GlobalId> taken;
  Real removed = 0;
  for (const Candidate& c : gather_candidates(mine, child.comm())) {
    if (!(owing[c.group] > 0) || taken.count(c.id)) continue;
    taken.insert(c.id);
    chosen.push_back(c.id);
    inserters_[c.group].extracted(c.mass);
    owing[c.group] -= c.mass;
    removed += c.mass;
  }
  if (!chosen.empty()) child.remove_particles(chosen);
  return removed;
}

std::int64_t Interface::insert(Level& child, const Level& parent) {
  return insert_flux(child, parent, inserters_);
}

Real Interface::remove_shadow(Level& parent, std::vector<Real> excess, const Vec3& near,
                              Real budget) {
  if (!(budget > 0)) return 0;
  const FieldGrid& g = grid_->grid();
  if (excess.size() != static_cast<std::size_t>(g.n_cells()))
    throw std::invalid_argument("Interface.remove_shadow: one excess per grid cell expected");
  const ParticleStore& ps = parent.particles();
  std::vector<Real> mine;  // cell, squared distance to its centre, id, mass, and to `near`
  for (Index i = 0; i < ps.n_owned(); ++i) {
    const Vec3& x = ps.position[i];
    const int c = g.cell_of(x);
    if (!grid_->inside(c)) continue;
    mine.insert(mine.end(), {static_cast<Real>(c), (x - g.centre(c)).squaredNorm(),
                             id_bits(ps.id[i]), ps.mass[i], (x - near).squaredNorm()});
  }
  const std::vector<Candidate> all = gather_candidates(mine, parent.comm());
  // Per cell, its candidates (sorted by distance to the centre) and the next one to take.
  std::vector<std::size_t> first(g.n_cells() + 1, all.size());
  for (std::size_t k = all.size(); k-- > 0;) first[all[k].group] = k;
  for (int c = g.n_cells(); c-- > 0;) first[c] = std::min(first[c], first[c + 1]);
  std::vector<std::size_t> next(first.begin(), first.end() - 1);
  std::vector<char> taken(all.size(), 0);
  std::vector<GlobalId> chosen;
  Real removed = 0;
  for (;;) {
    int best = -1;  // the cell with the largest excess that still has a candidate
    for (int c = 0; c < g.n_cells(); ++c)
      if (excess[c] > 0 && next[c] < first[c + 1] && (best < 0 || excess[c] > excess[best]))
        best = c;
    std::size_t pick = all.size();
    if (best >= 0) {
      pick = next[best]++;
    } else {  // no excess left: nearest to `near`
      Real d2 = INFINITY;
      GlobalId id = std::numeric_limits<GlobalId>::max();
      for (std::size_t k = 0; k < all.size(); ++k) {
        if (!taken[k] && std::tie(all[k].other, all[k].id) < std::tie(d2, id)) {
          d2 = all[k].other;
          id = all[k].id;
          pick = k;
        }
      }
    }
    if (pick == all.size() || removed + all[pick].mass > budget) break;
    taken[pick] = 1;
    chosen.push_back(all[pick].id);
    removed += all[pick].mass;
    excess[all[pick].group] -= all[pick].mass;
  }
  if (!chosen.empty()) parent.remove_particles(chosen);
  return removed;
}

void Interface::sample(Level& level, bool child) {
  (child ? child_average_ : parent_average_)
      .sample(level.particles(), level.last_stats(), level.domain());
}

CellFields Interface::finish_average(Level& level, bool child) {
  return (child ? child_average_ : parent_average_).finish(level.comm());
}

}  // namespace grainscale
