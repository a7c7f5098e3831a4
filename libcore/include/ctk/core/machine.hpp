#pragma once
// The machine a measurement was made on, as Linux names it: figures from two machines must not
// be mixed up, and a virtual machine's model name alone ("AMD EPYC") does not tell a Zen 3 from a
// Zen 5, so family and model come with it. And what a run held in memory at most.
#include <cstddef>
#include <nlohmann/json.hpp>

namespace ctk {

/// {"model_name", "family", "model"} of the first processor in /proc/cpuinfo (those found).
nlohmann::json cpu_identity();

/// The most memory this process has held resident so far (VmHWM in /proc/self/status; 0 where
/// Linux does not say).
std::size_t peak_resident_bytes();

}  // namespace ctk
