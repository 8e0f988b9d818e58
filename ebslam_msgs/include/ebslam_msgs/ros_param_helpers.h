#pragma once
// Parameter reading, checks and the one startup-failure policy of the workspace's nodelets (every
// ROS package of the workspace depends on ebslam_msgs).
//
// Policy (docs/ros_nodes_notes.md, "Startup policy"):
//   - a configuration that cannot work: the loader throws std::invalid_argument naming the fully
//     resolved parameter and the reason; startOrFail() logs it as FATAL and rethrows from
//     onInit(), so the nodelet is not loaded: a standalone node exits with status 1 and
//     `nodelet load` exits non-zero, which ends a launch where it is required="true";
//   - a parameter of the wrong type (e.g. a string where a number belongs) is such a failure;
//   - a private parameter that the node never read (misspelled, or of another node) is named in a
//     WARN with the closest parameter the node does read ("did you mean").

#include <ros/console.h>
#include <ros/node_handle.h>
#include <ros/param.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace ebslam_msgs {

namespace detail {

/// Fully resolved names of the parameters read through these helpers, in this process.
struct ReadParams {
  std::mutex mutex;
  std::set<std::string> names;
};

inline ReadParams& readParams() {
  static ReadParams registry;
  return registry;
}

inline const char* typeName(XmlRpc::XmlRpcValue::Type type) {
  switch (type) {
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return "a boolean";
    case XmlRpc::XmlRpcValue::TypeInt:
      return "an integer";
    case XmlRpc::XmlRpcValue::TypeDouble:
      return "a floating-point number";
    case XmlRpc::XmlRpcValue::TypeString:
      return "a string";
    case XmlRpc::XmlRpcValue::TypeArray:
      return "a list";
    case XmlRpc::XmlRpcValue::TypeStruct:
      return "a dictionary";
    default:
      return "of another type";
  }
}

template <typename T>
struct Expected {
  static bool accepts(XmlRpc::XmlRpcValue::Type) { return true; }  // checked by getParam itself
  static constexpr const char* kName = "of the documented type";
};
template <>
struct Expected<bool> {
  static bool accepts(XmlRpc::XmlRpcValue::Type t) { return t == XmlRpc::XmlRpcValue::TypeBoolean; }
  static constexpr const char* kName = "a boolean (true/false)";
};
template <>
struct Expected<int> {
  static bool accepts(XmlRpc::XmlRpcValue::Type t) { return t == XmlRpc::XmlRpcValue::TypeInt; }
  static constexpr const char* kName = "an integer";
};
template <>
struct Expected<double> {
  static bool accepts(XmlRpc::XmlRpcValue::Type t) {
    return t == XmlRpc::XmlRpcValue::TypeDouble || t == XmlRpc::XmlRpcValue::TypeInt;
  }
  static constexpr const char* kName = "a number";
};
template <>
struct Expected<float> : Expected<double> {};
template <>
struct Expected<std::string> {
  static bool accepts(XmlRpc::XmlRpcValue::Type t) { return t == XmlRpc::XmlRpcValue::TypeString; }
  static constexpr const char* kName = "a string";
};

/// Levenshtein distance (the "did you mean" of unknown parameters).
inline std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

}  // namespace detail

/// Records that the node reads parameter `name` of `nh` (for parameters read without param()).
inline void markParamRead(const ros::NodeHandle& nh, const std::string& name) {
  detail::ReadParams& registry = detail::readParams();
  const std::lock_guard<std::mutex> lock(registry.mutex);
  registry.names.insert(nh.resolveName(name));
}

/// Throws std::invalid_argument: parameter <resolved name> <why>.
[[noreturn]] inline void failParam(const ros::NodeHandle& nh, const std::string& name,
                                   const std::string& why) {
  throw std::invalid_argument("parameter " + nh.resolveName(name) + " " + why);
}

/// Throws std::invalid_argument when parameter `name` is set with a type other than T's.
template <typename T>
void requireType(const ros::NodeHandle& nh, const std::string& name) {
  XmlRpc::XmlRpcValue value;
  if (nh.getParam(name, value) && !detail::Expected<T>::accepts(value.getType())) {
    failParam(nh, name,
              std::string("must be ") + detail::Expected<T>::kName + ", is " +
                  detail::typeName(value.getType()));
  }
}

/// The parameter `name` of `nh`, or `default_value` where it is not set. Throws
/// std::invalid_argument where it is set with the wrong type (ROS would silently use the default).
template <typename T>
T param(const ros::NodeHandle& nh, const std::string& name, const T& default_value) {
  markParamRead(nh, name);
  requireType<T>(nh, name);
  T value;
  nh.param<T>(name, value, default_value);
  return value;
}

/// Throws std::invalid_argument unless `value` is finite and > 0.
inline void requirePositive(double value, const ros::NodeHandle& nh, const std::string& name) {
  if (!std::isfinite(value) || value <= 0.0) {
    throw std::invalid_argument("parameter " + nh.resolveName(name) + " = " +
                                std::to_string(value) + " must be a positive number");
  }
}

/// Marks the knobs of a dynamic_reconfigure Config type as read below `nh`: its Server reads them
/// at construction and writes them back, so they stay on the master for the node's next start.
template <typename ReconfigureConfig>
void markReconfigureParamsRead(const ros::NodeHandle& nh) {
  for (const auto& description : ReconfigureConfig::__getParamDescriptions__()) {
    markParamRead(nh, description->name);
  }
}

/// Names of the parameters set below `nh`'s namespace (fully resolved).
inline std::vector<std::string> paramsBelow(const ros::NodeHandle& nh) {
  std::vector<std::string> all, below;
  ros::param::getParamNames(all);
  const std::string prefix = nh.getNamespace() + "/";
  for (const std::string& name : all) {
    if (name.compare(0, prefix.size(), prefix) == 0) below.push_back(name);
  }
  return below;
}

/// One WARN per parameter of `set_names` that the node never read, with the closest name it
/// does read below the same namespace. Returns the unknown names.
inline std::vector<std::string> warnUnknownParams(const ros::NodeHandle& nh,
                                                  const std::vector<std::string>& set_names) {
  const std::string prefix = nh.getNamespace() + "/";
  std::vector<std::string> known;
  {
    detail::ReadParams& registry = detail::readParams();
    const std::lock_guard<std::mutex> lock(registry.mutex);
    for (const std::string& name : registry.names) {
      if (name.compare(0, prefix.size(), prefix) == 0) known.push_back(name);
    }
  }
  std::vector<std::string> unknown;
  for (const std::string& name : set_names) {
    // Read as a whole (e.g. a dictionary parameter read at once) or read exactly.
    const bool read = std::any_of(known.begin(), known.end(), [&](const std::string& k) {
      return name == k || name.compare(0, k.size() + 1, k + "/") == 0;
    });
    if (read) continue;
    unknown.push_back(name);
    std::string closest;
    std::size_t best = std::string::npos;
    for (const std::string& k : known) {
      const std::size_t d = detail::editDistance(name, k);
      if (d < best) {
        best = d;
        closest = k;
      }
    }
    if (closest.empty()) {
      ROS_WARN("parameter %s is not a parameter of this node: ignored", name.c_str());
    } else {
      ROS_WARN("parameter %s is not a parameter of this node: ignored (did you mean %s?)",
               name.c_str(), closest.c_str());
    }
  }
  return unknown;
}

/// The startup of a nodelet under the policy above: runs `start` (which reads its parameters
/// through these helpers); on an exception logs FATAL "<what> not started: <reason>" and rethrows
/// (from onInit() this unloads the nodelet); then warns about parameters it never read.
template <typename Start>
void startOrFail(const ros::NodeHandle& private_nh, const std::string& what, Start&& start) {
  // The parameters the user set, before the node's own servers (dynamic_reconfigure) add theirs.
  const std::vector<std::string> set_names = paramsBelow(private_nh);
  // Read by the nodes' diagnostic_updater::Updater, which takes the private node handle.
  markParamRead(private_nh, "diagnostic_period");
  try {
    start();
  } catch (const std::exception& error) {
    ROS_FATAL("%s not started: %s", what.c_str(), error.what());
    throw;
  }
  warnUnknownParams(private_nh, set_names);
}

}  // namespace ebslam_msgs
