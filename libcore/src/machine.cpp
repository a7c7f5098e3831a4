#include "ctk/core/machine.hpp"

#include <cstdlib>
#include <fstream>
#include <string>

namespace ctk {

nlohmann::json cpu_identity() {
  nlohmann::json cpu = nlohmann::json::object();
  std::ifstream info("/proc/cpuinfo");
  std::string line;
  while (std::getline(info, line) && !line.empty()) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string key = line.substr(0, colon);
    key.erase(key.find_last_not_of(" \t") + 1);
    const std::string value = colon + 2 <= line.size() ? line.substr(colon + 2) : "";
    if (key == "model name") cpu["model_name"] = value;
    if (key == "cpu family") cpu["family"] = std::atoi(value.c_str());
    if (key == "model") cpu["model"] = std::atoi(value.c_str());
  }
  return cpu;
}

std::size_t peak_resident_bytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return static_cast<std::size_t>(std::strtoull(line.c_str() + 6, nullptr, 10)) * 1024;  // kB
  return 0;
}

}  // namespace ctk
