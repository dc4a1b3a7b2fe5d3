#include "fragg_map/insert_stats.h"

namespace fragg {

void InsertStats::add(const InsertStats& o) {
  points_in += o.points_in;
  rays_hit += o.rays_hit;
  rays_free_only += o.rays_free_only;
  rays_no_return += o.rays_no_return;
  rays_dynamic += o.rays_dynamic;
  dropped_invalid += o.dropped_invalid;
  dropped_min_range += o.dropped_min_range;
  dropped_outside_frustum += o.dropped_outside_frustum;
  dropped_height += o.dropped_height;
  voxel_visits += o.voxel_visits;
  cells_updated += o.cells_updated;
  blocks_touched += o.blocks_touched;
  blocks_created += o.blocks_created;
  blocks_uploaded += o.blocks_uploaded;
  blocks_evicted += o.blocks_evicted;
  scans_staged += o.scans_staged;
  passes_redone += o.passes_redone;
  seconds_redone += o.seconds_redone;
  culling.add(o.culling);
  seconds_total += o.seconds_total;
  seconds_prepare += o.seconds_prepare;
  seconds_cull += o.seconds_cull;
  seconds_residency += o.seconds_residency;
  seconds_raycast += o.seconds_raycast;
  seconds_apply += o.seconds_apply;
}

}  // namespace fragg
