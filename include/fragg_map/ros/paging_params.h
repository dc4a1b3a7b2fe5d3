// The map server's out-of-core paging (issue 13): parameters paging/store, paging/budget_mb,
// paging/radius_m, paging/commit_every_scans, paging/commit_every_s, and the map they give:
// a new store is attached to an empty map, an existing store's map is continued.
#pragma once

#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <string>
#include <vector>

#include "fragg_map/map.h"
#include "fragg_map/page_store.h"

namespace fragg::ros {

struct PagingParams {
  /// paging/store: the page store's file ("": no paging). `.lmdb`/`.mdb`: LMDB, `.db`/
  /// `.sqlite`: SQLite, another name: LMDB where built (as `fragg_map build --page-store`).
  std::string store;
  /// paging/budget_mb, paging/radius_m [m], paging/commit_every_scans, paging/commit_every_s.
  fragg::PagingPolicy policy;
};

/// The names parsePagingParameters reads ("paging/store", ...): the server's unknown-parameter
/// check counts them as known.
const std::vector<std::string>& pagingParameterNames();

/// Reads paging/* from the private namespace (one XmlRpcValue; absent names keep their
/// defaults). With a store the map keeps no scans (the store holds none): keep_scans is
/// turned off in `map`, and an explicit keep_scans: true is refused. Throws
/// fragg::InvalidArgument naming the parameter ('paging/budget_mb') for a wrong type or value,
/// and for a budget or radius > 0 without paging/store.
PagingParams parsePagingParameters(const XmlRpc::XmlRpcValue& params, fragg::MapParams* map);

/// Reads the node's private namespace and parses it as above.
PagingParams readPagingParameters(const ::ros::NodeHandle& private_nh, fragg::MapParams* map);

/// The server's map: in memory without a store; with one, the store's map continued when it
/// holds one (its resolution and occupancy model must be the parameters'), else an empty map
/// that pages to it. Throws InvalidArgument (the store's map has another resolution or
/// occupancy model; built without page stores) or
/// IoError (the store cannot be opened or read).
fragg::Map makeServerMap(const fragg::MapParams& map, const PagingParams& paging);

}  // namespace fragg::ros
