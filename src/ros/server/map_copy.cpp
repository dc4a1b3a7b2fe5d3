// observedCopy: Map::extract over the observed cells' bounds.
#include "map_copy.h"

#include <Eigen/Core>

namespace fragg::ros {

fragg::Map observedCopy(const fragg::Map& map) {
  const fragg::KeyBounds bounds = map.bounds();
  if (bounds.empty) return map.extract(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  // Cell centres are inside the box by a quarter cell: no rounding at its faces.
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(0.25 * map.resolution());
  return map.extract(map.centerOf(bounds.min) - margin, map.centerOf(bounds.max) + margin);
}

}  // namespace fragg::ros
