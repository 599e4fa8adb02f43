// Visitors over options structs: print as YAML, apply key=value overrides, validate.
#pragma once
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "common/option.hpp"

namespace lodforge {

template <class T> struct is_vector : std::false_type {};
template <class T> struct is_vector<std::vector<T>> : std::true_type {};

// Writes "key: value  # help" lines, nested by section.
class OptionPrinter {
 public:
  template <class T>
  void operator()(const char* name, T& value, const char* help, const Check& = {}) {
    out_ << std::string(2 * depth_, ' ') << name << ": " << format(value) << "  # " << help << '\n';
  }
  template <class S>
  void section(const char* name, S& options) {
    out_ << std::string(2 * depth_, ' ') << name << ":\n";
    ++depth_;
    options.visit(*this);
    --depth_;
  }
  std::string str() const { return out_.str(); }

 private:
  template <class T>
  static std::string format(const T& value) {
    std::ostringstream s;
    if constexpr (std::is_same_v<T, bool>) s << (value ? "true" : "false");
    else if constexpr (is_vector<T>::value) {
      s << '[';
      for (std::size_t i = 0; i < value.size(); ++i) s << (i ? ", " : "") << format(value[i]);
      s << ']';
    } else if constexpr (std::is_same_v<T, std::string>) s << (value.empty() ? "\"\"" : value);
    else s << value;
    return s.str();
  }
  std::ostringstream out_;
  int depth_ = 0;
};

// Collects "path: problem" for every value outside its Check.
class OptionValidator {
 public:
  template <class T>
  void operator()(const char* name, T& value, const char*, const Check& check = {}) {
    std::string p;
    if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) p = check.problem(double(value));
    else if constexpr (std::is_same_v<T, std::string>) p = check.problem(value);
    else if constexpr (is_vector<T>::value) {
      for (const auto& item : value) {
        if constexpr (std::is_arithmetic_v<typename T::value_type>) p = check.problem(double(item));
        else p = check.problem(item);
        if (!p.empty()) break;
      }
    }
    if (!p.empty()) errors.push_back(prefix_ + name + ": " + p);
  }
  template <class S>
  void section(const char* name, S& options) {
    const std::string saved = prefix_;
    prefix_ += std::string(name) + ".";
    options.visit(*this);
    prefix_ = saved;
  }
  std::vector<std::string> errors;

 private:
  std::string prefix_;
};

// Applies "section.key" -> "text" overrides; records unknown keys and unparsable values.
class OptionSetter {
 public:
  explicit OptionSetter(std::map<std::string, std::string> values) : values_(std::move(values)) {}
  template <class T>
  void operator()(const char* name, T& value, const char*, const Check& = {}) {
    const std::string key = prefix_ + name;
    auto it = values_.find(key);
    if (it == values_.end()) return;
    if (!parse(it->second, value)) errors.push_back(key + ": cannot read '" + it->second + "'");
    values_.erase(it);
  }
  template <class S>
  void section(const char* name, S& options) {
    const std::string saved = prefix_;
    prefix_ += std::string(name) + ".";
    options.visit(*this);
    prefix_ = saved;
  }
  // Call after visiting: every key that matched no option is an error.
  void report_unknown() {
    for (const auto& [key, _] : values_) errors.push_back(key + ": unknown option");
    values_.clear();
  }
  std::vector<std::string> errors;

 private:
  template <class T>
  static bool parse(const std::string& text, T& value) {
    if constexpr (std::is_same_v<T, bool>) {
      if (text == "true" || text == "1") { value = true; return true; }
      if (text == "false" || text == "0") { value = false; return true; }
      return false;
    } else if constexpr (std::is_same_v<T, std::string>) {
      value = text;
      return true;
    } else if constexpr (is_vector<T>::value) {
      T parsed;
      std::stringstream s(text);
      std::string item;
      while (std::getline(s, item, ',')) {
        typename T::value_type v{};
        if (!parse(item, v)) return false;
        parsed.push_back(v);
      }
      value = parsed;
      return true;
    } else {
      std::istringstream s(text);
      T parsed{};
      s >> parsed;
      if (s.fail() || !s.eof()) return false;
      value = parsed;
      return true;
    }
  }
  std::map<std::string, std::string> values_;
  std::string prefix_;
};

// Applies "path" -> "text" values to options, then validates them; every problem (unknown key,
// unreadable value, value out of range) is appended to errors with its key path.
template <class Options>
void set_and_validate(Options& options, std::map<std::string, std::string> values, std::vector<std::string>& errors) {
  OptionSetter setter(std::move(values));
  options.visit(setter);
  setter.report_unknown();
  errors.insert(errors.end(), setter.errors.begin(), setter.errors.end());
  OptionValidator validator;
  options.visit(validator);
  errors.insert(errors.end(), validator.errors.begin(), validator.errors.end());
}

}  // namespace lodforge
