// Level: scheduled insertion and outlets (the per-step hook of run()).
#include "level/level.hpp"

namespace grainscale {

void Level::apply_insertions_and_outlets() {
  // No inserters or outlets exist yet; the insertion module fills this hook.
}

}  // namespace grainscale
