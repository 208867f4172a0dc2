#include "contact/hertz_mindlin.hpp"

#include "core/errors.hpp"

namespace grainscale {

HertzMindlin::HertzMindlin(const HertzMindlinSettings& s) : settings_(s) {
  if (!(s.restitution >= 0 && s.restitution <= 1))
    throw_invalid("HertzMindlin.restitution", "in [0, 1]", s.restitution);
  if (!(s.friction >= 0) || !std::isfinite(s.friction))
    throw_invalid("HertzMindlin.friction", "non-negative and finite", s.friction);
}

void HertzMindlin::prepare(const MaterialTable& materials) {
  stride_ = materials.n_materials() + 1;
  pairs_.assign(static_cast<std::size_t>(stride_) * stride_, Pair{});
  const Real damping = -2 * std::sqrt(5.0 / 6.0) * restitution_beta(settings_.restitution);
  for (int i = 0; i < stride_; ++i)
    for (int j = 0; j < stride_; ++j) {
      if (i == materials.rigid_index() && j == materials.rigid_index()) continue;
      const PairModuli m = materials.pair_moduli(i, j);
      pairs_[i * stride_ + j] = {m.effective_youngs, m.effective_shear, damping,
                                 settings_.friction};
    }
}

}  // namespace grainscale
