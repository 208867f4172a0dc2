#include "integrate/velocity_verlet.hpp"

#include <algorithm>

namespace grainscale {

template <bool kClosingKick>
Real kick_drift(ParticleStore& ps, Real dt, const Vec3& gravity,
                const std::vector<Vec3>& reference) {
  const Real half = 0.5 * dt;
  const Index n = ps.n_owned();
  Vec3* x = ps.position.data();
  Vec3* v = ps.velocity.data();
  Vec3* w = ps.angular_velocity.data();
  Vec3* f = ps.force.data();
  Vec3* t = ps.torque.data();
  const Real* m = ps.mass.data();
  const Real* im = ps.inv_mass.data();
  const Real* ii = ps.inv_inertia.data();
  Real max_d2 = 0;
  for (Index i = 0; i < n; ++i) {
    const Vec3 dv = (half * im[i]) * f[i];
    const Vec3 dw = (half * ii[i]) * t[i];
    if constexpr (kClosingKick) {
      v[i] += dv;
      w[i] += dw;
    }
    v[i] += dv;
    w[i] += dw;
    x[i] += dt * v[i];
    f[i] = m[i] * gravity;
    t[i].setZero();
    const Real d2 = (x[i] - reference[i]).squaredNorm();
    if (d2 > max_d2 || d2 != d2) max_d2 = d2;  // a NaN sticks, so it forces a (checked) rebuild
  }
  return max_d2;
}

template Real kick_drift<false>(ParticleStore&, Real, const Vec3&, const std::vector<Vec3>&);
template Real kick_drift<true>(ParticleStore&, Real, const Vec3&, const std::vector<Vec3>&);

void kick(ParticleStore& ps, Real dt) {
  const Real half = 0.5 * dt;
  const Index n = ps.n_owned();
  Vec3* v = ps.velocity.data();
  Vec3* w = ps.angular_velocity.data();
  const Vec3* f = ps.force.data();
  const Vec3* t = ps.torque.data();
  const Real* im = ps.inv_mass.data();
  const Real* ii = ps.inv_inertia.data();
  for (Index i = 0; i < n; ++i) {
    v[i] += (half * im[i]) * f[i];
    w[i] += (half * ii[i]) * t[i];
  }
}

}  // namespace grainscale
