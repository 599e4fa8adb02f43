// Reads an options tree from YAML through the same visit() declarations that print and
// validate it. Every problem (unknown key, wrong type) is collected with its key path.
#pragma once
#include <set>
#include <string>
#include <type_traits>
#include <vector>
#include <yaml-cpp/yaml.h>

#include "common/option_visitors.hpp"

namespace lodforge {

class YamlReader {
 public:
  explicit YamlReader(const YAML::Node& root) { nodes_.push_back(root); }

  template <class T>
  void operator()(const char* name, T& value, const char*, const Check& = {}) {
    const YAML::Node& map = nodes_.back();
    seen_.back().insert(name);
    if (!map.IsMap() || !map[name]) return;
    const YAML::Node node = map[name];
    const std::string path = prefix_ + name;
    if (node.IsNull()) return;
    if constexpr (is_vector<T>::value) {
      if (!node.IsSequence()) { errors.push_back(path + ": expected a list"); return; }
      T parsed;
      for (std::size_t i = 0; i < node.size(); ++i) {
        typename T::value_type item{};
        if (!scalar(node[i], item)) {
          errors.push_back(path + "[" + std::to_string(i) + "]: expected " + type_name<typename T::value_type>());
          return;
        }
        parsed.push_back(item);
      }
      value = parsed;
    } else if (!scalar(node, value)) {
      errors.push_back(path + ": expected " + type_name<T>());
    }
  }

  template <class S>
  void section(const char* name, S& options) {
    const YAML::Node& map = nodes_.back();
    seen_.back().insert(name);
    YAML::Node child = map.IsMap() && map[name] ? map[name] : YAML::Node(YAML::NodeType::Map);
    const std::string path = prefix_ + name;
    if (child.IsNull()) child = YAML::Node(YAML::NodeType::Map);
    if (!child.IsMap()) { errors.push_back(path + ": expected a mapping of options"); return; }
    const std::string saved = prefix_;
    prefix_ = path + ".";
    nodes_.push_back(child);
    seen_.emplace_back();
    options.visit(*this);
    report_unknown();
    seen_.pop_back();
    nodes_.pop_back();
    prefix_ = saved;
  }

  // Reports the keys of the current mapping that no declaration read, and keys given twice
  // (YAML forbids them; yaml-cpp would silently read the first).
  void report_unknown() {
    const YAML::Node& map = nodes_.back();
    if (!map.IsMap()) return;
    std::set<std::string> keys;
    for (auto it = map.begin(); it != map.end(); ++it) {
      const std::string key = it->first.as<std::string>();
      if (!keys.insert(key).second) {
        errors.push_back(prefix_ + key + ": given twice (line " + std::to_string(it->first.Mark().line + 1) + "); give each key once");
        continue;
      }
      if (!seen_.back().count(key)) errors.push_back(prefix_ + key + ": unknown key");
    }
  }

  std::vector<std::string> errors;

 private:
  template <class T>
  static bool scalar(const YAML::Node& node, T& value) {
    if (!node.IsScalar()) return false;
    try {
      if constexpr (std::is_same_v<T, bool>) value = node.as<bool>();
      else if constexpr (std::is_integral_v<T>) {
        const std::string text = node.Scalar();
        if (text.find_first_of(".eE") != std::string::npos) return false;
        value = node.as<T>();
      } else value = node.as<T>();
      return true;
    } catch (const YAML::Exception&) {
      return false;
    }
  }
  template <class T>
  static std::string type_name() {
    if constexpr (std::is_same_v<T, bool>) return "true or false";
    else if constexpr (std::is_integral_v<T>) return "an integer";
    else if constexpr (std::is_arithmetic_v<T>) return "a number";
    else return "a string";
  }
  std::vector<YAML::Node> nodes_;
  std::vector<std::set<std::string>> seen_{{}};
  std::string prefix_;
};

}  // namespace lodforge
