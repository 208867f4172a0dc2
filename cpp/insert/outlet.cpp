#include "insert/outlet.hpp"

#include <limits>
#include <sstream>

#include "core/errors.hpp"

namespace grainscale {

Outlet::Outlet(const OutletSpec& spec, Real time) : spec_(spec) {
  if (spec.every < 1) throw_invalid("Outlet.every", "a positive number of steps", spec.every);
  time_.push_back(time);
  mass_.push_back(0);
  count_.push_back(0);
}

void Outlet::record(Real time, std::int64_t count, Real mass) {
  removed_count_ += count;
  removed_mass_ += mass;
  time_.push_back(time);
  mass_.push_back(removed_mass_);
  count_.push_back(removed_count_);
}

std::string Outlet::save_state() const {
  std::ostringstream out;
  out.precision(std::numeric_limits<Real>::max_digits10);
  out << "outlet-v1 " << removed_count_ << ' ' << removed_mass_ << ' ' << time_.size();
  for (std::size_t k = 0; k < time_.size(); ++k)
    out << ' ' << time_[k] << ' ' << mass_[k] << ' ' << count_[k];
  return out.str();
}

void Outlet::load_state(const std::string& state) {
  std::istringstream in(state);
  std::string tag;
  std::int64_t count = 0;
  Real mass = 0;
  std::size_t n = 0;
  in >> tag >> count >> mass >> n;
  std::vector<Real> t(in ? n : 0), m(t.size());
  std::vector<std::int64_t> c(t.size());
  for (std::size_t k = 0; k < t.size(); ++k) in >> t[k] >> m[k] >> c[k];
  if (tag != "outlet-v1" || in.fail())
    throw_invalid("Outlet state", "text written by get_state() of an outlet", "'" + tag + " ...'");
  removed_count_ = count;
  removed_mass_ = mass;
  time_.swap(t);
  mass_.swap(m);
  count_.swap(c);
}

}  // namespace grainscale
