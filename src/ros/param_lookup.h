// Lookups in the map server's parameter tree (one XmlRpcValue of the private namespace),
// shared by the parameter readers of src/ros (server, autosave, paging).
#pragma once

#include <xmlrpcpp/XmlRpcValue.h>

#include <string>

#include "fragg_map/errors.h"

namespace fragg::ros {

/// Throws InvalidArgument naming the parameter and what is wrong with it.
[[noreturn]] inline void badParam(const std::string& name, const std::string& problem) {
  throw fragg::InvalidArgument("parameter '" + name + "': " + problem);
}

/// root[group][name] (group empty: root[name]) when there, else nullptr.
[[nodiscard]] inline const XmlRpc::XmlRpcValue* paramMember(const XmlRpc::XmlRpcValue& root,
                                                            const char* group, const char* name) {
  using XmlRpc::XmlRpcValue;
  if (root.getType() != XmlRpcValue::TypeStruct) return nullptr;
  XmlRpcValue& r = const_cast<XmlRpcValue&>(root);
  if (*group == '\0') return r.hasMember(name) ? &r[name] : nullptr;
  if (!r.hasMember(group)) return nullptr;
  XmlRpcValue& g = r[group];
  if (g.getType() != XmlRpcValue::TypeStruct || !g.hasMember(name)) return nullptr;
  return &g[name];
}

}  // namespace fragg::ros
