#include "insert/outlet.hpp"

#include <limits>
#include <sstream>

#include "core/errors.hpp"

namespace grainscale {

Outlet::Outlet(const OutletSpec& spec, Real time) : spec_(spec) {
  if (spec.every < 1) throw_invalid("Outlet.every", "a positive number of steps", spec.every);
  face_mass_.assign(spec.keep_faces, 0);
  time_.push_back(time);
  mass_.push_back(0);
  count_.push_back(0);
}

void Outlet::record(Real time, std::int64_t count, Real mass, const Vec3& moment,
                    const std::vector<Real>& face_mass) {
  removed_count_ += count;
  removed_mass_ += mass;
  moment_ += moment;
  for (std::size_t f = 0; f < face_mass_.size() && f < face_mass.size(); ++f)
    face_mass_[f] += face_mass[f];
  time_.push_back(time);
  mass_.push_back(removed_mass_);
  count_.push_back(removed_count_);
}

std::string Outlet::save_state() const {
  std::ostringstream out;
  out.precision(std::numeric_limits<Real>::max_digits10);
  out << "outlet-v2 " << removed_count_ << ' ' << removed_mass_ << ' ' << time_.size();
  for (std::size_t k = 0; k < time_.size(); ++k)
    out << ' ' << time_[k] << ' ' << mass_[k] << ' ' << count_[k];
  out << ' ' << moment_[0] << ' ' << moment_[1] << ' ' << moment_[2] << ' ' << face_mass_.size();
  for (Real m : face_mass_) out << ' ' << m;
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
  // v1 (before the moment and the face masses): none booked.
  Vec3 moment = Vec3::Zero();
  std::vector<Real> faces(face_mass_.size(), 0);
  if (tag == "outlet-v2") {
    std::size_t nf = 0;
    in >> moment[0] >> moment[1] >> moment[2] >> nf;
    if (in && nf != faces.size()) in.setstate(std::ios::failbit);
    for (std::size_t f = 0; in && f < nf; ++f) in >> faces[f];
  }
  if ((tag != "outlet-v1" && tag != "outlet-v2") || in.fail())
    throw_invalid("Outlet state", "text written by get_state() of an outlet", "'" + tag + " ...'");
  removed_count_ = count;
  moment_ = moment;
  face_mass_.swap(faces);
  removed_mass_ = mass;
  time_.swap(t);
  mass_.swap(m);
  count_.swap(c);
}

}  // namespace grainscale
