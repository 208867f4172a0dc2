#include "contact/contact_law.hpp"

#include <utility>

#include "core/errors.hpp"

namespace grainscale {

namespace {

template <std::size_t... I>
std::vector<std::string> names(std::index_sequence<I...>) {
  return {std::variant_alternative_t<I, ContactLaw>::name()...};
}

template <std::size_t I = 0>
bool make(const std::string& wanted, const ContactSettings& s, ContactLaw& out) {
  if constexpr (I < std::variant_size_v<ContactLaw>) {
    using Law = std::variant_alternative_t<I, ContactLaw>;
    if (Law::name() == wanted) {
      out.template emplace<I>(s);
      return true;
    }
    return make<I + 1>(wanted, s, out);
  } else {
    return false;
  }
}

}  // namespace

std::vector<std::string> supported_contact_laws() {
  return names(std::make_index_sequence<std::variant_size_v<ContactLaw>>{});
}

ContactLaw make_contact_law(const std::string& normal, const std::string& rolling,
                            const ContactSettings& settings) {
  ContactLaw law{std::in_place_index<0>, settings};
  const std::string wanted = normal + "+" + rolling;
  if (make(wanted, settings, law)) return law;
  std::string list;
  for (const std::string& n : supported_contact_laws()) list += (list.empty() ? "" : ", ") + n;
  throw_invalid("contact law (normal+rolling)", "one of: " + list, wanted);
}

}  // namespace grainscale
