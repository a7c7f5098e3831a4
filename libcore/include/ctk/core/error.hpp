#pragma once
// Errors caused by a user's input: each names the file, the place in it (a key path such as
// "detector.pixel_pitch_mm[1]" or a line such as "line 12"), and what was expected.
#include <filesystem>
#include <stdexcept>
#include <string>

namespace ctk {

/// The place of a JSON key, as every InputError names one: "key 'views[3].P'".
std::string json_key(const std::string& path);

class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string where, const std::string& what);

  const std::string& file() const { return file_; }
  const std::string& where() const { return where_; }

 private:
  std::string file_;
  std::string where_;
};

/// `message` with every word longer than 160 characters cut to its head and tail and its length: a
/// value pasted by mistake (a 400-digit number, a whole file on one line) is not echoed in full.
std::string with_long_words_clipped(const std::string& message);

/// An options struct checking itself: unless `ok`, throws std::invalid_argument
/// "<field>: expected <expected>, got <value>" (field as "SirtOptions.relaxation").
void require_option(bool ok, const char* field, const char* expected, double value);
/// The same for a named choice ("diagonal").
void require_choice(bool ok, const char* field, const char* expected, const char* value);

/// Readers open only regular files: a pipe would wait for a writer forever and a device (/dev/zero)
/// never ends. Throws InputError naming the file when it is missing or not a regular file.
void require_regular_file(const std::filesystem::path& file);

}  // namespace ctk
