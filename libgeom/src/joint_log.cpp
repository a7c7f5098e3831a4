#include "ctk/geom/joint_log.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"

namespace ctk {

namespace {

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) {
    const auto b = cell.find_first_not_of(" \t\r");
    const auto e = cell.find_last_not_of(" \t\r");
    cells.push_back(b == std::string::npos ? std::string() : cell.substr(b, e - b + 1));
  }
  return cells;
}

double parse_number(const std::string& cell, const std::string& file, const std::string& where) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(cell, &used);
  } catch (const std::exception&) {
    throw InputError(file, where, "expected a number, got '" + cell + "'");
  }
  if (used != cell.size()) throw InputError(file, where, "expected a number, got '" + cell + "'");
  if (!std::isfinite(v)) throw InputError(file, where, "expected a finite number, got '" + cell + "'");
  return v;
}

}  // namespace

JointLog JointLog::read(const std::filesystem::path& path, int view_count) {
  const std::string file = path.string();
  require_regular_file(path);
  std::ifstream in(path);
  if (!in) throw InputError(file, "", "cannot open the joint log");
  std::string line;
  if (!std::getline(in, line)) throw InputError(file, "line 1", "empty file; expected the header view,q1,...,q7");
  const std::vector<std::string> expected{"view", "q1", "q2", "q3", "q4", "q5", "q6", "q7"};
  if (split_csv(line) != expected) throw InputError(file, "line 1", "expected the header view,q1,q2,q3,q4,q5,q6,q7");

  JointLog log;
  log.row_of_view_.assign(static_cast<std::size_t>(std::max(view_count, 0)), -1);
  int line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::string where = "line " + std::to_string(line_number);
    const auto cells = split_csv(line);
    if (cells.size() != 8)
      throw InputError(file, where, "expected 8 values (view and 7 joints), got " + std::to_string(cells.size()));
    const double view_value = parse_number(cells[0], file, where + ", column view");
    if (view_value != std::floor(view_value)) throw InputError(file, where + ", column view", "expected a whole view index");
    const int view = static_cast<int>(view_value);
    if (view < 0 || view >= view_count)
      throw InputError(file, where + ", column view",
                       "view " + std::to_string(view) + " outside the scan's projections (count " + std::to_string(view_count) +
                           "): the joint log does not match projections.count");
    if (log.row_of_view_[static_cast<std::size_t>(view)] >= 0)
      throw InputError(file, where, "view " + std::to_string(view) + " appears twice");
    panda::Joints q{};
    for (std::size_t j = 0; j < q.size(); ++j)
      q[j] = parse_number(cells[j + 1], file, where + ", column q" + std::to_string(j + 1));
    log.add(view, q);
  }
  return log;
}

void JointLog::add(int view, const panda::Joints& q) {
  if (view >= static_cast<int>(row_of_view_.size())) row_of_view_.resize(static_cast<std::size_t>(view) + 1, -1);
  row_of_view_[static_cast<std::size_t>(view)] = static_cast<int>(rows_.size());
  rows_.push_back({view, q, panda::describe_limit_violations(q)});
}

const JointRow* JointLog::find(int view) const {
  if (view < 0 || view >= static_cast<int>(row_of_view_.size())) return nullptr;
  const int i = row_of_view_[static_cast<std::size_t>(view)];
  return i < 0 ? nullptr : &rows_[static_cast<std::size_t>(i)];
}

void JointLog::write(const std::filesystem::path& file) const {
  write_file_atomically(file, [&](std::ostream& out) {
    out << "view,q1,q2,q3,q4,q5,q6,q7\n";
    out.precision(17);
    for (const auto& row : rows_) {
      out << row.view;
      for (double q : row.q) out << ',' << q;
      out << '\n';
    }
  });
}

}  // namespace ctk
