// Errors caused by the user's input: reported as one clear message, non-zero exit.
#pragma once
#include <stdexcept>
#include <string>
#include <vector>

namespace lodforge {

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A command line that cannot be parsed (unknown option, missing value): exit code 2.
struct UsageError : InputError {
  using InputError::InputError;
};

// Several problems found at once (e.g. every invalid option), reported together.
inline InputError input_errors(const std::vector<std::string>& problems) {
  std::string text;
  for (const std::string& p : problems) text += (text.empty() ? "" : "\n") + p;
  return InputError(text);
}

}  // namespace lodforge
