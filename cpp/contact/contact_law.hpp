// The registry of supported contact laws: one row (variant alternative) per combination of
// sub-models. The step loop is instantiated once per row and selected once per run() call
// (std::visit), never per contact. Adding a law: a sub-model struct (normal_models.hpp,
// rolling_models.hpp, ...) and a row here.
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "contact/contact_model.hpp"

namespace grainscale {

template <class Normal, class Damping>
using WithRolling = std::variant<
    ContactModel<Normal, Damping, NoRolling>, ContactModel<Normal, Damping, CDTRolling>,
    ContactModel<Normal, Damping, EPSDRolling>, ContactModel<Normal, Damping, EPSD2Rolling>>;

using ContactLaw = std::variant<
    // Hertz–Mindlin with LIGGGHTS-type nonlinear damping (the default law)
    ContactModel<HertzNormal, HertzDamping, NoRolling>,
    ContactModel<HertzNormal, HertzDamping, CDTRolling>,
    ContactModel<HertzNormal, HertzDamping, EPSDRolling>,
    ContactModel<HertzNormal, HertzDamping, EPSD2Rolling>,
    // linear spring–dashpot
    ContactModel<LinearNormal, ViscousDamping, NoRolling>,
    ContactModel<LinearNormal, ViscousDamping, CDTRolling>,
    ContactModel<LinearNormal, ViscousDamping, EPSDRolling>,
    ContactModel<LinearNormal, ViscousDamping, EPSD2Rolling>,
    // EEPA (bilinear elasto-plastic adhesive)
    ContactModel<EEPANormal, ViscousDamping, NoRolling>,
    ContactModel<EEPANormal, ViscousDamping, CDTRolling>,
    ContactModel<EEPANormal, ViscousDamping, EPSDRolling>,
    ContactModel<EEPANormal, ViscousDamping, EPSD2Rolling>>;

// Names of the supported laws, "normal+rolling" (e.g. "hertz+epsd").
std::vector<std::string> supported_contact_laws();

// The law for `normal` and `rolling` model names; InvalidArgument listing the supported ones
// for any other combination.
ContactLaw make_contact_law(const std::string& normal, const std::string& rolling,
                            const ContactSettings& settings);

inline int history_size(const ContactLaw& law) {
  return std::visit([](const auto& l) { return std::decay_t<decltype(l)>::kHistorySize; }, law);
}

inline std::string law_name(const ContactLaw& law) {
  return std::visit([](const auto& l) { return std::decay_t<decltype(l)>::name(); }, law);
}

}  // namespace grainscale
