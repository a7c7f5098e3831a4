#include "ctk/core/error.hpp"

#include <algorithm>
#include <sstream>

namespace ctk {

static std::string compose_message(const std::string& file, const std::string& where, const std::string& what) {
  std::string message = file;
  if (!where.empty()) message += ": " + where;
  return message + ": " + with_long_words_clipped(what);
}

std::string with_long_words_clipped(const std::string& message) {
  constexpr std::size_t longest = 160, head = 60, tail = 30;
  std::string out;
  std::size_t i = 0;
  while (i < message.size()) {
    const std::size_t end = std::min(message.find_first_of(" \t\n", i), message.size());
    if (end - i > longest) {
      out.append(message, i, head);
      out += "...";
      out.append(message, end - tail, tail);
      out += " (" + std::to_string(end - i) + " characters)";
    } else {
      out.append(message, i, end - i);
    }
    if (end < message.size()) out += message[end];
    i = end + 1;
  }
  return out;
}

std::string json_key(const std::string& path) { return "key '" + path + "'"; }

namespace {

template <typename Value>
void require_option_of(bool ok, const char* field, const char* expected, const Value& value) {
  if (ok) return;
  std::ostringstream message;
  message << field << ": expected " << expected << ", got " << value;
  throw std::invalid_argument(with_long_words_clipped(message.str()));
}

}  // namespace

void require_option(bool ok, const char* field, const char* expected, double value) {
  require_option_of(ok, field, expected, value);
}

void require_choice(bool ok, const char* field, const char* expected, const char* value) {
  require_option_of(ok, field, expected, value);
}

InputError::InputError(std::string file, std::string where, const std::string& what)
    : std::runtime_error(compose_message(file, where, what)), file_(std::move(file)), where_(std::move(where)) {}

void require_regular_file(const std::filesystem::path& file) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(file, ec)) return;
  throw InputError(file.string(), "",
                   std::filesystem::exists(file, ec) ? "not a regular file (a folder, a pipe or a device)" : "no such file");
}

}  // namespace ctk
