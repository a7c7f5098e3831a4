#include "ctk/core/provenance.hpp"

#include <mutex>

#include "git_version.h"

namespace ctk {

namespace {

std::mutex invocation_mutex;
std::string& invocation_text() {
  static std::string text = "library call";
  return text;
}

// A word that the shell would split or expand is quoted, so the line can be pasted back.
std::string shell_word(const std::string& word) {
  if (!word.empty() && word.find_first_of(" \t\n'\"\\$`*?[]{}()<>|&;#~!") == std::string::npos) return word;
  std::string quoted = "'";
  for (char c : word) {
    if (c == '\'')
      quoted.append("'\\''");
    else
      quoted.push_back(c);
  }
  quoted.push_back('\'');
  return quoted;
}

}  // namespace

std::string build_version() { return std::string(CTK_VERSION) + " (" + CTK_GIT_DESCRIBE + ")"; }

void set_invocation(std::string invocation) {
  const std::lock_guard<std::mutex> lock(invocation_mutex);
  invocation_text() = std::move(invocation);
}

void set_invocation(int argc, const char* const* argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) {
    if (i) line.push_back(' ');
    line.append(shell_word(argv[i]));
  }
  set_invocation(std::move(line));
}

nlohmann::json provenance() {
  std::string invocation;
  {
    const std::lock_guard<std::mutex> lock(invocation_mutex);
    invocation = invocation_text();
  }
  return {{"ctk_version", build_version()}, {"invocation", invocation}};
}

}  // namespace ctk
