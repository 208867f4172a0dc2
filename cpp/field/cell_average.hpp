// Cell averages of one level on a FieldGrid (DESIGN.md 2.7, 4): per cell the mass, the Favre
// (mass-weighted) velocity, the solid fraction, the stress tensor, the range of the particle
// velocities and their spread, averaged over the samples taken since the last finish().
//
// A particle belongs to the cell of its centre (positions wrapped on periodic axes). With S
// samples of a cell of volume V:
//   mass            M = (1/S) sum_s sum_i m_i
//   solid fraction  phi = (1/(S V)) sum_s sum_i v_i   (v_i the particle volume; disc area x 1 m
//                   in 2-D)
//   velocity        u = sum_s sum_i m_i v_i / sum_s sum_i m_i        (Favre average)
//   spread          s_a = sqrt(K_aa / M - u_a^2), per component: the mass-weighted standard
//                   deviation of the particle velocities about u (K below)
//   stress          sigma = (1/V) [ K - P P^T / M  +  W ],  compression positive, with
//                   K = (1/S) sum m v v^T, P = (1/S) sum m v (the kinetic part: the velocity
//                   fluctuations about the cell's mean over the interval) and the contact virial
//                   W = (1/S) sum_s sum_contacts F (x - c)^T: each contact adds F (x_i - c) to
//                   the cell of i and -F (x_j - c) to the cell of j, c = x_i - (r_i - delta/2) n
//                   the contact point, F the force on i (a wall contact adds only i's part).
// For a bed in static equilibrium on a floor at z = 0, the zz virial summed over all cells is
// sum_i m_i g z_i + sum_floor F_z delta / 2 (each particle's contact forces balance its weight;
// a wall contact point sits delta / 2 below the floor, mid-overlap); Christoffersen, Mehrabadi &
// Nemat-Nasser 1981, J. Appl. Mech. 48:339 derive the mean stress of an assembly this way.
// tests/unit/test_fields.py checks the identity with the particles' total forces.
//
// Under MPI every rank samples its owned particles and the contacts it computed (each contact
// is computed on one rank); finish() sums the cells over the ranks (in rank order).
#pragma once

#include <array>
#include <vector>

#include "contact/contact_stats.hpp"
#include "field/field_grid.hpp"
#include "parallel/communicator.hpp"
#include "state/domain.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

struct CellFields {
  FieldGrid grid;
  int samples = 0;
  std::vector<Real> mass;                        // kg
  std::vector<Real> solid_fraction;              // particle volume / cell volume
  std::vector<Vec3> velocity;                    // m/s, Favre; zero in empty cells
  std::vector<std::array<Real, 9>> stress;       // Pa, row-major, compression positive
  std::vector<Vec3> velocity_min, velocity_max;  // component-wise over particles and samples
  // m/s, per component: the mass-weighted standard deviation of the particle velocities about
  // the Favre velocity over particles and samples, sqrt(K_aa / M - u_a^2)
  std::vector<Vec3> velocity_spread;
  std::vector<Real> particles;  // mean number of particles
};

class CellAverager {
 public:
  // dimension 2: particle volumes are disc areas x 1 m (the level's 2-D mode).
  CellAverager(const FieldGrid& grid, int dimension);

  // One sample of the owned particles and of `stats.records` (the contacts of the last force
  // evaluation, recorded with local indices into `ps`).
  void sample(const ParticleStore& ps, const ContactStats& stats, const Domain& domain);
  int samples() const { return samples_; }
  // Collective: the averages over the samples, summed over the ranks; starts a new interval.
  CellFields finish(const Communicator& comm);

 private:
  FieldGrid grid_;
  int dimension_ = 3;
  int samples_ = 0;
  // Per cell: mass, volume, count, momentum (3), K (9), W (9) = 24 sums.
  std::vector<Real> sums_;
  std::vector<Real> vmin_, vmax_;  // 3 per cell
};

}  // namespace grainscale
