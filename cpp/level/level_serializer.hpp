// LevelSerializer: writes a level's checkpoint state and reads it back (DESIGN.md 2.7) — the
// particles, ghost stages, decomposition, contact lists and scalars itself, the walls' and the
// inserters' parts through their owners (WallSet, Insertion). Level::save_state, load_state,
// load_redistributed and signature call it; see level/level.hpp for what each guarantees.
#pragma once

#include <string>
#include <vector>

#include "core/types.hpp"
#include "level/level_state.hpp"

namespace grainscale {

class Level;

class LevelSerializer {
 public:
  // Completes any pending list rebuild and set-up force evaluation first — exactly what the
  // next run() would do first — so the saved state is the one a continuing run steps from.
  static LevelState save(Level& level);
  static void load(Level& level, const LevelState& state);
  static void load_redistributed(Level& level, const std::vector<LevelState>& states);
  // Every check a load makes, before anything changes: counts, list offsets and partners,
  // ids, ghost stages, walls and inserter states. `exact`: the state is loaded as this rank's
  // (ghosts and lists kept); `n_materials`: the materials the restart will have registered.
  // Throws std::runtime_error naming what is damaged; load() and load_redistributed() call it.
  static void validate(const Level& level, const LevelState& state, bool exact, int n_materials);
  // The set-up a state belongs to (law, counts of materials, walls, inserters; periodicity).
  static std::string signature(const Level& level);
  // The same with `n_materials` registered (a restart registers the checkpoint's first).
  static std::string signature(const Level& level, int n_materials);

 private:
  static void check_signature(const Level& level, const LevelState& state, int n_materials);
  // Scalars shared by every rank's state; `lost` and `lost_mass` are the rank's own.
  static void load_scalars(Level& level, const LevelState& state, std::int64_t lost,
                           Real lost_mass);
};

}  // namespace grainscale
