#include "ctk/core/json_access.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>

namespace ctk {

namespace {

// A number as a reader wrote it (1e-300, not 0.000000; 1e+308, not 310 digits).
std::string shortest(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// The last "key": before byte `offset`, to tell the user where a syntax error sits.
std::string key_before(const std::string& text, std::size_t offset) {
  offset = std::min(offset, text.size());
  std::size_t colon = text.rfind(':', offset == 0 ? 0 : offset - 1);
  while (colon != std::string::npos && colon > 0) {
    std::size_t close = text.find_last_not_of(" \t\r\n", colon - 1);
    if (close != std::string::npos && text[close] == '"') {
      std::size_t open = text.rfind('"', close - 1);
      if (open != std::string::npos) return text.substr(open + 1, close - open - 1);
    }
    if (colon == 0) break;
    colon = text.rfind(':', colon - 1);
  }
  return {};
}

// Whether the literal at byte `offset` is a non-finite number as Python's json module writes
// them (NaN, Infinity, -Infinity; also nan, inf): JSON has none, and the parser's own message
// ("invalid literal") does not say why such a file fails.
bool non_finite_literal_at(const std::string& text, std::size_t offset) {
  offset = std::min(offset, text.size());
  std::size_t start = text.find_last_of(" \t\r\n:,[{", offset == 0 ? 0 : offset - 1);
  start = start == std::string::npos ? 0 : start + 1;
  if (start > offset) start = offset;
  if (start < text.size() && (text[start] == '-' || text[start] == '+')) ++start;
  std::string word = text.substr(start, 3);
  std::transform(word.begin(), word.end(), word.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return word == "nan" || word == "inf";
}

std::string type_name(const nlohmann::json& v) {
  if (v.is_number()) return "a number";
  if (v.is_string()) return "a string \"" + v.get<std::string>() + "\"";
  return std::string(v.type_name());
}

}  // namespace

nlohmann::json read_json_file(const std::filesystem::path& file) {
  require_regular_file(file);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "", "cannot open the file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  // Where in the text a problem sits: "line L, column C (key 'k')".
  auto position = [&](std::size_t offset) {
    offset = std::min(offset, text.size());
    const std::size_t line =
        1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(offset), '\n'));
    const std::size_t line_start = offset == 0 ? std::string::npos : text.rfind('\n', offset - 1);
    const std::size_t column = offset - (line_start == std::string::npos ? 0 : line_start + 1) + 1;
    std::string where = "line " + std::to_string(line) + ", column " + std::to_string(column);
    const std::string key = key_before(text, offset);
    if (!key.empty()) where += " (key '" + key + "')";
    return where;
  };
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    const std::size_t at = e.byte == 0 ? 0 : e.byte - 1;
    throw InputError(file.string(), position(at),
                     std::string(non_finite_literal_at(text, at) ? "not valid JSON (NaN and Infinity are not JSON numbers): "
                                                                 : "not valid JSON: ") +
                         e.what());
  } catch (const nlohmann::json::out_of_range& e) {
    // A number too large for a double ("1e999"): the message quotes the literal; find it.
    const std::string what = e.what();
    const auto q0 = what.find('\''), q1 = what.rfind('\'');
    const std::size_t at = q0 != std::string::npos && q1 > q0 ? text.find(what.substr(q0 + 1, q1 - q0 - 1)) : std::string::npos;
    throw InputError(file.string(), at == std::string::npos ? std::string() : position(at),
                     "number out of range (not a finite double): " + what);
  }
}

JsonNode::JsonNode(const nlohmann::json& value, std::string file, std::string path, std::vector<std::string>* warnings)
    : value_(&value), file_(std::move(file)), path_(std::move(path)), warnings_(warnings) {}

void JsonNode::fail(const std::string& what) const {
  throw InputError(file_, path_.empty() ? std::string("top level") : json_key(path_), what);
}

void JsonNode::expect_object() const {
  if (!value_->is_object()) fail("expected an object, got " + type_name(*value_));
}

bool JsonNode::has(std::string_view key) const { return value_->is_object() && value_->contains(key); }

JsonNode JsonNode::at(std::string_view key) const {
  expect_object();
  const std::string child = path_.empty() ? std::string(key) : path_ + "." + std::string(key);
  auto it = value_->find(key);
  if (it == value_->end()) throw InputError(file_, json_key(child), "missing (required)");
  return JsonNode(*it, file_, child, warnings_);
}

std::optional<JsonNode> JsonNode::find(std::string_view key) const {
  expect_object();
  auto it = value_->find(key);
  if (it == value_->end() || it->is_null()) return std::nullopt;
  return JsonNode(*it, file_, path_.empty() ? std::string(key) : path_ + "." + std::string(key), warnings_);
}

JsonNode JsonNode::at(std::size_t index) const {
  if (!value_->is_array()) fail("expected an array, got " + type_name(*value_));
  if (index >= value_->size())
    fail("has " + std::to_string(value_->size()) + " elements, index " + std::to_string(index) + " requested");
  return JsonNode((*value_)[index], file_, path_ + "[" + std::to_string(index) + "]", warnings_);
}

std::size_t JsonNode::size() const {
  if (!value_->is_array()) fail("expected an array, got " + type_name(*value_));
  return value_->size();
}

double JsonNode::number() const {
  if (!value_->is_number()) fail("expected a number, got " + type_name(*value_));
  const double v = value_->get<double>();
  if (!std::isfinite(v)) fail("expected a finite number, got " + shortest(v));
  return v;
}

void require_same_run(const nlohmann::json& saved, const nlohmann::json& now, const std::string& file, const std::string& prefix,
                      const std::string& advice) {
  for (const auto& [key, value] : now.items())
    if (!saved.is_object() || !saved.contains(key) || saved.at(key) != value) {
      std::string what = "was ";
      what += saved.is_object() && saved.contains(key) ? saved.at(key).dump() : std::string("absent");
      what += " in the saved run; this run has ";
      what += value.dump();
      what += ": ";
      what += advice;
      std::string where = prefix;
      where += '.';
      where += key;
      throw InputError(file, json_key(where), what);
    }
}

double JsonNode::positive_number() const {
  const double v = number();
  if (!(v > 0)) fail("expected a positive number, got " + shortest(v));
  return v;
}

double JsonNode::length_mm() const {
  const double v = positive_number();
  if (v < kShortestLengthMm || v > kLongestLengthMm)
    fail("expected a length between " + shortest(kShortestLengthMm) + " and " + shortest(kLongestLengthMm) + " mm, got " +
         shortest(v));
  return v;
}

int JsonNode::integer() const {
  const double v = number();
  if (v != std::floor(v) || std::abs(v) > 2e9) fail("expected an integer, got " + shortest(v));
  return static_cast<int>(v);
}

std::string JsonNode::string() const {
  if (!value_->is_string()) fail("expected a string, got " + type_name(*value_));
  return value_->get<std::string>();
}

bool JsonNode::boolean() const {
  if (!value_->is_boolean()) fail("expected true or false, got " + type_name(*value_));
  return value_->get<bool>();
}

std::vector<double> JsonNode::numbers(std::optional<std::size_t> expected_size) const {
  const std::size_t n = size();
  if (expected_size && n != *expected_size)
    fail("expected " + std::to_string(*expected_size) + " numbers, got " + std::to_string(n));
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = at(i).number();
  return out;
}

Eigen::Matrix3d JsonNode::matrix3() const {
  if (size() != 3) fail("expected a 3x3 matrix (3 rows), got " + std::to_string(size()) + " rows");
  Eigen::Matrix3d M;
  for (int r = 0; r < 3; ++r) {
    const auto row = at(static_cast<std::size_t>(r)).numbers(3);
    for (int c = 0; c < 3; ++c) M(r, c) = row[static_cast<std::size_t>(c)];
  }
  return M;
}

Eigen::Vector3d JsonNode::vector3() const {
  const auto v = numbers(3);
  return {v[0], v[1], v[2]};
}

Eigen::Vector3d JsonNode::position_mm() const {
  Eigen::Vector3d p = vector3();
  if (p.cwiseAbs().maxCoeff() > kLongestLengthMm)
    fail("expected coordinates within " + shortest(kLongestLengthMm) + " mm of the origin, got " +
         shortest(p.cwiseAbs().maxCoeff()));
  return p;
}

void JsonNode::warn_unknown_keys(std::initializer_list<std::string_view> known) const {
  if (!warnings_ || !value_->is_object()) return;
  for (const auto& item : value_->items()) {
    if (std::find(known.begin(), known.end(), item.key()) == known.end()) {
      const std::string key = path_.empty() ? item.key() : path_ + "." + item.key();
      warnings_->push_back(file_ + ": key '" + key + "' is not part of the format; ignored");
    }
  }
}

}  // namespace ctk
