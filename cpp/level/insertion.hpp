// Insertion: what adds and removes particles of a level by schedule — packing into a region,
// stream inserters and outlets, the per-step hook that runs the outlets and streams inside
// Level::run, and their part of a checkpoint. See insert/*.hpp for the algorithms and their
// bookkeeping. Particles are placed through the level's placement primitive
// (Level::insertion_site, Level::place_particles), which other floors (coupling/) use as well.
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "field/exchange_grid.hpp"
#include "insert/occupancy_grid.hpp"
#include "insert/outlet.hpp"
#include "insert/pack.hpp"
#include "insert/stream.hpp"
#include "insert/wall_clearance.hpp"
#include "level/level_state.hpp"
#include "state/material_table.hpp"

namespace grainscale {

class Level;

// Where new particles go: the occupancy of every rank's particles near an insertion box and the
// walls' clearance there.
struct InsertionSite {
  OccupancyGrid grid;
  WallClearance walls;
};

// The region of a region outlet: it removes the particles farther than `band` (m) from the
// grid's region cells (the fine level of a hierarchy: particles leaving its region; the band
// keeps the grains its insertion shells place with the centre just outside a face) and books
// them per interface face (the nearest one); the outlet's own region is not used.
struct OutletKeep {
  std::shared_ptr<const ExchangeGrid> grid;
  Real band = 0;
};

class Insertion {
 public:
  // Level::pack: validates, places and adds the particles (collective).
  std::pair<GlobalId, Index> pack(Level& level, const PackSpec& spec);
  // Validated against the level's set-up; returns the index.
  int add_stream(const Level& level, const StreamSpec& spec);
  int add_outlet(const OutletSpec& spec, Real time, OutletKeep keep = OutletKeep());
  std::vector<StreamInserter>& streams() { return streams_; }
  const std::vector<StreamInserter>& streams() const { return streams_; }
  std::vector<Outlet>& outlets() { return outlets_; }
  const std::vector<Outlet>& outlets() const { return outlets_; }
  // Smallest Rayleigh time (s) of the particles the streams may insert (inf without streams).
  Real smallest_rayleigh_time(const MaterialTable& materials) const;

  // The per-step hook, once per step after the drift (collective): outlets first (removing
  // particles frees room for the inserters of the same step), then the streams due.
  void step(Level& level);

  // Checkpoint: the complete mutable state of every stream and outlet as text.
  void save_state(LevelState& s) const;
  void load_state(const LevelState& s);
  // The checks of load_state on copies, changing nothing (throws on a damaged state).
  void check_state(const LevelState& s) const;

 private:
  void apply_outlets(Level& level);
  void run_streams(Level& level);

  std::vector<StreamInserter> streams_;
  std::vector<Outlet> outlets_;
  std::vector<OutletKeep> keeps_;  // per outlet
};

}  // namespace grainscale
