// Inputs shared by the loop-closure tests: a room scanned from a few poses.
#pragma once

#include <Eigen/Geometry>
#include <cmath>

#include "../core/test_scenes.h"
#include "fragg_map/interop/compare.h"
#include "fragg_map/map.h"

namespace fragg::test {

/// The i-th pose of a short walk through the room (0.3 m steps, a few degrees of yaw).
inline Eigen::Isometry3d poseAt(int i, double dx_m = 0.0, double dyaw_rad = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.3 * i + dx_m, 0.1 * i, 0.02);
  T.linear() = Eigen::AngleAxisd(0.05 * i + dyaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

inline SensorModel lidar() { return SensorModel::spinningLidar(-0.6, 0.6, 0.0, 10.0); }

/// Cells observed in either map with the same state in both, as a fraction.
inline double sameState(const Map& a, const Map& b) {
  return compareMaps(a, b).agreementInEither();
}

/// Whether every cell (log-odds and hit count) is the same in both maps; blocks without an
/// observed cell count as absent.
inline bool sameCells(const Map& a, const Map& b, std::string* why = nullptr) {
  auto covered = [](const Map& x, const Map& y, std::string* msg) {
    bool ok = true;
    const BlockView by = y.blockView();
    x.forEachBlock([&](const BlockKey& k, const Block& block) {
      if (!ok) return;
      const Block* other = by.findBlock(k);
      for (int c = 0; c < kCellsPerBlock && ok; ++c) {
        const Cell& cx = block.cells[c];
        const Cell cy = other ? other->cells[c] : Cell();
        if (cx.log_odds_fx != cy.log_odds_fx || cx.hits != cy.hits) {
          ok = false;
          if (msg)
            *msg = "block (" + std::to_string(k.x) + "," + std::to_string(k.y) + "," +
                   std::to_string(k.z) + ") cell " + std::to_string(c) + ": " +
                   std::to_string(cx.log_odds_fx) + "/" + std::to_string(cx.hits) + " vs " +
                   std::to_string(cy.log_odds_fx) + "/" + std::to_string(cy.hits);
        }
      }
    });
    return ok;
  };
  return covered(a, b, why) && covered(b, a, why);
}

}  // namespace fragg::test
