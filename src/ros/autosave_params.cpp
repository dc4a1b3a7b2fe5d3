#include "fragg_map/ros/autosave_params.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "fragg_map/errors.h"
#include "param_lookup.h"

namespace fragg::ros {

namespace {
using XmlRpc::XmlRpcValue;
namespace fs = std::filesystem;

std::string readString(const XmlRpcValue* v, const std::string& name) {
  XmlRpcValue copy = *v;
  if (copy.getType() != XmlRpcValue::TypeString) badParam(name, "expected a string");
  return static_cast<std::string>(copy);
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}
}  // namespace

const std::vector<std::string>& autosaveParameterNames() {
  static const std::vector<std::string> names = {"autosave/path", "autosave/period_s", "file_root"};
  return names;
}

std::string defaultFileRoot() {
  const char* ros_home = std::getenv("ROS_HOME");
  if (ros_home && *ros_home) return (fs::path(ros_home) / "fragg_map").string();
  const char* home = std::getenv("HOME");
  return (fs::path(home && *home ? home : "/tmp") / ".ros" / "fragg_map").string();
}

std::string resolveAutosavePath(const std::string& path, const std::string& file_root) {
  if (path.empty()) throw fragg::InvalidArgument("autosave/path: empty path");
  if (!endsWith(path, ".fgm"))
    throw fragg::InvalidArgument("autosave/path '" + path + "': the autosave is a .fgm file");
  const fs::path given(path);
  if (given.is_absolute()) return given.lexically_normal().string();
  const fs::path root(file_root);
  if (!root.is_absolute())
    throw fragg::InvalidArgument("file_root '" + file_root + "': expected an absolute folder");
  const fs::path relative = given.lexically_normal();
  if (relative.empty() || *relative.begin() == "..")
    throw fragg::InvalidArgument("autosave/path '" + path + "' leaves file_root " + file_root);
  return (root.lexically_normal() / relative).lexically_normal().string();
}

AutosaveParams parseAutosaveParameters(const XmlRpcValue& root) {
  AutosaveParams p;
  p.file_root = defaultFileRoot();
  if (const XmlRpcValue* v = paramMember(root, "", "file_root")) {
    const std::string given = readString(v, "file_root");
    if (!given.empty()) {  // "" keeps the default, as for the file services
      if (!fs::path(given).is_absolute()) badParam("file_root", "expected an absolute folder");
      p.file_root = given;
    }
  }
  if (const XmlRpcValue* v = paramMember(root, "autosave", "period_s")) {
    XmlRpcValue copy = *v;
    if (copy.getType() == XmlRpcValue::TypeDouble)
      p.period_s = static_cast<double>(copy);
    else if (copy.getType() == XmlRpcValue::TypeInt)
      p.period_s = static_cast<int>(copy);
    else
      badParam("autosave/period_s", "expected a number of seconds");
    if (!std::isfinite(p.period_s) || p.period_s < 0)
      badParam("autosave/period_s", "expected a finite number >= 0 (0: on shutdown only)");
  }
  if (const XmlRpcValue* v = paramMember(root, "autosave", "path")) {
    const std::string given = readString(v, "autosave/path");
    if (!given.empty()) {
      try {
        p.path = resolveAutosavePath(given, p.file_root);
      } catch (const fragg::InvalidArgument& e) {
        badParam("autosave/path", e.what());
      }
    }
  }
  if (p.period_s > 0 && p.path.empty())
    badParam("autosave/period_s", "needs autosave/path (the file to save to)");
  return p;
}

}  // namespace fragg::ros
