#pragma once
// The flat yaml of map and scenario files (ROS-free): one `key: value` per line, scalars or
// [a, b, c] lists kept as text, '#' comments, optional quotes around a value.

#include <map>
#include <string>

namespace ebslam_ros {

/// Keys and their values as text. Throws std::runtime_error naming the file (and line) when it
/// cannot be opened or a line is not `key: value`; `what` names the kind of file in the message.
std::map<std::string, std::string> readFlatYaml(const std::string& path,
                                                const std::string& what = "yaml");
/// `file` as named in the yaml at `yaml_path`: absolute as is, relative to the yaml's folder.
std::string resolveBesideYaml(const std::string& file, const std::string& yaml_path);

}  // namespace ebslam_ros
