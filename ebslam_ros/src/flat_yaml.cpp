#include "ebslam_ros/flat_yaml.h"

#include <fstream>
#include <stdexcept>

namespace ebslam_ros {
namespace {

std::string trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  const auto end = s.find_last_not_of(" \t\r");
  return s.substr(begin, end - begin + 1);
}

}  // namespace

std::map<std::string, std::string> readFlatYaml(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + what + " '" + path + "'");
  std::map<std::string, std::string> values;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    line = trim(line);
    if (line.empty()) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) {
      throw std::runtime_error(what + " " + path + ":" + std::to_string(number) +
                               ": not a 'key: value' line");
    }
    std::string value = trim(line.substr(colon + 1));
    if (value.size() >= 2 && (value.front() == '"' || value.front() == '\'') &&
        value.back() == value.front()) {
      value = value.substr(1, value.size() - 2);
    }
    values[trim(line.substr(0, colon))] = value;
  }
  return values;
}

std::string resolveBesideYaml(const std::string& file, const std::string& yaml_path) {
  if (!file.empty() && file.front() == '/') return file;
  const auto slash = yaml_path.find_last_of('/');
  return slash == std::string::npos ? file : yaml_path.substr(0, slash + 1) + file;
}

}  // namespace ebslam_ros
