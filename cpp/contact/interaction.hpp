// Interaction: the properties of one material pair (or material–wall pair) that the contact
// laws read. Python fills one per pair after applying the mixing rules (see contact.py); the
// laws turn them into their own per-pair constants in prepare().
#pragma once

#include "core/types.hpp"

namespace grainscale {

struct Interaction {
  Real restitution = 0.5;
  Real friction = 0.5;
  Real rolling_friction = 0;  // mu_r
  Real rolling_damping = 0;   // eta_r (EPSD)
  // Linear spring–dashpot: k_n (N/m) given, or derived from E*, R* and a characteristic
  // velocity (LIGGGHTS normal_model_hooke) when normal_stiffness <= 0.
  Real normal_stiffness = 0;
  Real tangential_stiffness = 0;  // <= 0: 2/7 k_n
  Real characteristic_velocity = 1;
  // EEPA (Thakur et al.): exponent n, k1 (<= 0: derived from E*, R*), k2/k1, k_adh, f0, chi.
  Real eepa_exponent = 1;
  Real loading_stiffness = 0;
  Real unloading_ratio = 3;
  Real adhesive_stiffness = 0;
  Real pull_off_force = 0;  // f0, added to every branch (<= 0 attracts)
  Real adhesion_exponent = 1;
};

}  // namespace grainscale
