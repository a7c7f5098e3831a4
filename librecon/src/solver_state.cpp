#include "ctk/recon/solver_state.hpp"

#include <boost/crc.hpp>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/json_access.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/core/provenance.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {

constexpr const char* kFormat = "ctk-solver-state/1";

void write_floats(std::ostream& out, const FloatBuffer& v) {
  out.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(float)));
}

// CRC-32 of the header (without its checksum) and of every vector's bytes, as 8 hex digits: a
// flipped bit anywhere, in the numbers or in the description of the run they belong to, is found.
std::string checksum(const nlohmann::json& head_without_checksum, const std::vector<const FloatBuffer*>& vectors) {
  boost::crc_32_type crc;
  const std::string text = head_without_checksum.dump();
  crc.process_bytes(text.data(), text.size());
  for (const FloatBuffer* v : vectors) crc.process_bytes(v->data(), v->size() * sizeof(float));
  std::ostringstream hex;
  hex << std::hex << std::setw(8) << std::setfill('0') << crc.checksum();
  return hex.str();
}

}  // namespace

void check_solver_state(const SolverState& s, const std::string& solver, const std::vector<std::size_t>& vector_lengths,
                        std::size_t scalars, const VolumeLayout& layout) {
  std::vector<std::size_t> lengths;
  for (const FloatBuffer& v : s.vectors) lengths.push_back(v.size());
  if (s.solver != solver || lengths != vector_lengths || s.scalars.size() != scalars || !(s.x.layout == layout) || s.log.empty())
    throw std::invalid_argument("a saved state of " + s.solver + " cannot continue this " + solver + " run (other sizes)");
}

void write_solver_state(const SolverSnapshot& s, const nlohmann::json& run, const fs::path& file) {
  nlohmann::json log = nlohmann::json::array();
  for (const IterationLog& l : s.log)
    log.push_back({l.iteration, l.cost, l.data_term, l.regulariser_term, l.relative_gradient, l.seconds});
  std::vector<std::size_t> lengths;
  for (const FloatBuffer* v : s.vectors) lengths.push_back(v->size());
  const auto& l = s.x.layout;
  nlohmann::json head = {{"format", kFormat},
                         {"provenance", provenance()},
                         {"solver", s.solver},
                         {"iteration", s.iteration},
                         {"log", log},
                         {"scalars", s.scalars},
                         {"vector_lengths", lengths},
                         {"volume",
                          {{"size", l.size},
                           {"voxel_mm", {l.voxel_mm.x(), l.voxel_mm.y(), l.voxel_mm.z()}},
                           {"origin_mm", {l.origin_mm.x(), l.origin_mm.y(), l.origin_mm.z()}}}},
                         {"run", run}};
  std::vector<const FloatBuffer*> all = {&s.x.data};
  all.insert(all.end(), s.vectors.begin(), s.vectors.end());
  head["crc32"] = checksum(head, all);
  // Saved now, not with the run's outputs: it must survive the run being stopped.
  const OutputSet::Outside now;
  write_file_atomically(file, [&](std::ostream& out) {
    out << head.dump() << "\n";
    write_floats(out, s.x.data);
    for (const FloatBuffer* v : s.vectors) write_floats(out, *v);
  });
}

SolverState read_solver_state(const fs::path& file, nlohmann::json& run) {
  require_regular_file(file);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "", "cannot open the solver state");
  std::string line;
  if (!std::getline(in, line) || line.size() > (1u << 26))
    throw InputError(file.string(), "", "not a ctk solver state (no header line)");
  nlohmann::json head;
  try {
    head = nlohmann::json::parse(line);
  } catch (const nlohmann::json::exception&) {
    throw InputError(file.string(), "", "not a ctk solver state (the header is not JSON)");
  }
  const JsonNode node(head, file.string(), "");
  if (node.at("format").string() != kFormat) node.at("format").fail(std::string("expected \"") + kFormat + "\"");
  SolverState s;
  s.solver = node.at("solver").string();
  s.iteration = node.at("iteration").integer();
  const JsonNode log = node.at("log");
  for (std::size_t i = 0; i < log.size(); ++i) {
    const auto v = log.at(i).numbers(6);
    s.log.push_back({static_cast<int>(v[0]), v[1], v[2], v[3], v[4], v[5]});
  }
  s.scalars = node.at("scalars").numbers();
  const JsonNode volume = node.at("volume");
  VolumeLayout layout;
  const auto size = volume.at("size").numbers(3);
  for (std::size_t a = 0; a < 3; ++a) {
    if (!(size[a] >= 1 && size[a] <= 1e5 && size[a] == std::floor(size[a])))
      volume.at("size").fail("expected three voxel counts");
    layout.size[a] = static_cast<int>(size[a]);
  }
  layout.voxel_mm = volume.at("voxel_mm").vector3();
  layout.origin_mm = volume.at("origin_mm").vector3();
  std::vector<std::size_t> lengths;
  const JsonNode lengths_node = node.at("vector_lengths");
  for (std::size_t i = 0; i < lengths_node.size(); ++i) lengths.push_back(static_cast<std::size_t>(lengths_node.at(i).number()));
  // The vectors' sizes are checked against the file's before anything is allocated.
  std::uintmax_t expected = layout.voxel_count();
  for (std::size_t n : lengths) expected += n;
  const std::uintmax_t data_bytes = fs::file_size(file) - line.size() - 1;
  if (data_bytes != expected * sizeof(float))
    throw InputError(file.string(), "",
                     "holds " + std::to_string(data_bytes) + " bytes of vectors, its header announces " +
                         std::to_string(expected * sizeof(float)) + " (a truncated or damaged state)");
  s.x = Volume(layout);
  auto read = [&](FloatBuffer& v) {
    in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(float)));
  };
  read(s.x.data);
  for (std::size_t n : lengths) {
    s.vectors.emplace_back(n);
    read(s.vectors.back());
  }
  if (!in) throw InputError(file.string(), "", "could not be read to its end");
  if (head.contains("crc32")) {  // states of earlier builds have none
    const std::string stored = node.at("crc32").string();
    nlohmann::json described = head;
    described.erase("crc32");
    std::vector<const FloatBuffer*> all = {&s.x.data};
    for (const FloatBuffer& v : s.vectors) all.push_back(&v);
    if (checksum(described, all) != stored)
      throw InputError(file.string(), "key 'crc32'",
                       "does not match the state's content (a damaged file): start again without --resume, or delete it");
  }
  run = head.at("run");
  return s;
}

}  // namespace ctk
