#pragma once
// Checked access to JSON input files. Every failure is an InputError naming the file and the key
// path ("holder.spheres_mm[3][2]"); numbers must be finite; unknown keys become warnings.
#include <Eigen/Core>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ctk/core/error.hpp"

namespace ctk {

/// Parses a JSON file; a syntax error is reported with line, column and the nearest key.
nlohmann::json read_json_file(const std::filesystem::path& file);

/// A saved run's description against this run's: the first key of `now` that `saved` does not
/// hold with the same value is refused (InputError on `file`, key `prefix.key`, both values and
/// `advice`). For state that only the run that saved it may continue.
void require_same_run(const nlohmann::json& saved, const nlohmann::json& now, const std::string& file, const std::string& prefix,
                      const std::string& advice);

class JsonNode {
 public:
  /// `warnings` (optional) collects notes about unknown keys.
  JsonNode(const nlohmann::json& value, std::string file, std::string path, std::vector<std::string>* warnings = nullptr);

  bool has(std::string_view key) const;
  JsonNode at(std::string_view key) const;                   // required key
  std::optional<JsonNode> find(std::string_view key) const;  // optional key
  JsonNode at(std::size_t index) const;                      // array element
  std::size_t size() const;                                  // array length (must be an array)

  double number() const;  // finite number
  double positive_number() const;
  /// A positive length no CT setup leaves: between a nanometre and a kilometre. Beyond it the
  /// matrices built from it overflow or become singular.
  double length_mm() const;
  static constexpr double kShortestLengthMm = 1e-6, kLongestLengthMm = 1e6;
  int integer() const;
  std::string string() const;
  bool boolean() const;
  std::vector<double> numbers(std::optional<std::size_t> expected_size = std::nullopt) const;
  Eigen::Matrix3d matrix3() const;  // [[a,b,c],[d,e,f],[g,h,i]]
  Eigen::Vector3d vector3() const;
  Eigen::Vector3d position_mm() const;  // each coordinate within kLongestLengthMm

  /// Adds a warning for every key of this object not in `known`.
  void warn_unknown_keys(std::initializer_list<std::string_view> known) const;

  [[noreturn]] void fail(const std::string& what) const;
  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  const nlohmann::json& raw() const { return *value_; }

 private:
  void expect_object() const;
  const nlohmann::json* value_;
  std::string file_;
  std::string path_;
  std::vector<std::string>* warnings_;
};

}  // namespace ctk
