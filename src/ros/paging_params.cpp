#include "fragg_map/ros/paging_params.h"

#include <cmath>
#include <string>

#include "fragg_map/errors.h"
#include "param_lookup.h"
#ifdef FRAGG_HAVE_PAGE_STORE
#include "fragg_map/store/page_stores.h"
#endif

namespace fragg::ros {

namespace {
using XmlRpc::XmlRpcValue;

/// paging/<name> into *out when given; true when given.
bool readNumber(const XmlRpcValue& root, const char* name, double* out) {
  const XmlRpcValue* v = paramMember(root, "paging", name);
  if (!v) return false;
  XmlRpcValue copy = *v;
  if (copy.getType() == XmlRpcValue::TypeDouble)
    *out = static_cast<double>(copy);
  else if (copy.getType() == XmlRpcValue::TypeInt)
    *out = static_cast<int>(copy);
  else
    badParam(std::string("paging/") + name, "expected a number");
  if (!std::isfinite(*out) || *out < 0)
    badParam(std::string("paging/") + name, "expected a finite number >= 0");
  return true;
}
}  // namespace

const std::vector<std::string>& pagingParameterNames() {
  static const std::vector<std::string> names = {
      "paging/store",          "paging/budget_mb",
      "paging/radius_m",       "paging/commit_every_scans",
      "paging/commit_every_s", "paging/low_water",
      "paging/read_ahead_rays"};
  return names;
}

PagingParams parsePagingParameters(const XmlRpcValue& root, fragg::MapParams* map) {
  PagingParams p;
  if (const XmlRpcValue* v = paramMember(root, "paging", "store")) {
    XmlRpcValue copy = *v;
    if (copy.getType() != XmlRpcValue::TypeString) badParam("paging/store", "expected a string");
    p.store = static_cast<std::string>(copy);
  }
  readNumber(root, "budget_mb", &p.policy.budget_mb);
  readNumber(root, "radius_m", &p.policy.radius_m);
  double every_scans = static_cast<double>(p.policy.commit_every_scans);
  if (readNumber(root, "commit_every_scans", &every_scans)) {
    if (every_scans != std::floor(every_scans))
      badParam("paging/commit_every_scans", "expected a whole number of scans");
    p.policy.commit_every_scans = static_cast<uint64_t>(every_scans);
  }
  readNumber(root, "commit_every_s", &p.policy.commit_every_s);
  readNumber(root, "low_water", &p.policy.low_water);
  double rays = static_cast<double>(p.policy.read_ahead_rays);
  if (readNumber(root, "read_ahead_rays", &rays)) {
    if (rays != std::floor(rays) || rays > 1e9)
      badParam("paging/read_ahead_rays", "expected a whole number of rays (0: every ray)");
    p.policy.read_ahead_rays = static_cast<size_t>(rays);
  }
  if (p.store.empty()) {
    if (p.policy.budget_mb > 0 || p.policy.radius_m > 0)
      badParam(p.policy.budget_mb > 0 ? "paging/budget_mb" : "paging/radius_m",
               "needs paging/store (the page store file)");
    return p;
  }
  // The store holds blocks, not scans: a paging map keeps none.
  if (root.getType() == XmlRpcValue::TypeStruct && root.hasMember("keep_scans")) {
    XmlRpcValue keep = const_cast<XmlRpcValue&>(root)["keep_scans"];
    if (keep.getType() == XmlRpcValue::TypeBoolean && static_cast<bool>(keep))
      badParam("paging/store", "a map that keeps its scans (keep_scans: true) cannot page");
  }
  map->scans.keep = false;
  try {
    p.policy.validate();
  } catch (const fragg::InvalidArgument& e) {
    // readNumber checked the others already: the policy's own rule refuses low_water, and
    // its message names it.
    const bool low_water = std::string(e.what()).find("low_water") != std::string::npos;
    badParam(low_water ? "paging/low_water" : "paging/budget_mb", e.what());
  }
  return p;
}

PagingParams readPagingParameters(const ::ros::NodeHandle& private_nh, fragg::MapParams* map) {
  XmlRpcValue root;  // stays invalid (every default) when the namespace holds nothing
  private_nh.getParam(private_nh.getNamespace(), root);
  return parsePagingParameters(root, map);
}

fragg::Map makeServerMap(const fragg::MapParams& map, const PagingParams& paging) {
  if (paging.store.empty()) return fragg::Map(map);
#ifdef FRAGG_HAVE_PAGE_STORE
  // An empty map takes a store's map (scans and blocks, paged out) when it holds one, after
  // checking its resolution and occupancy model; else the store starts empty.
  fragg::Map server_map(map);
  server_map.attachPageStore(fragg::openPageStore(paging.store, false), paging.policy);
  return server_map;
#else
  throw fragg::InvalidArgument("paging/store: this fragg_map was built without page stores");
#endif
}

}  // namespace fragg::ros
