#pragma once
// Which build made an output and how it was asked for: every JSON file the toolkit writes
// carries this record under "provenance", so a result found months later names its producer.
#include <string>

#include <nlohmann/json.hpp>

namespace ctk {

/// "0.4.0 (commit description)": the project version and `git describe` of the build's source.
std::string build_version();

/// The invocation recorded in outputs from now on: a program's main passes its argv, the Python
/// binding the call it serves. Until set, outputs record "library call".
void set_invocation(std::string invocation);
void set_invocation(int argc, const char* const* argv);

/// {"ctk_version", "invocation"}; no clock time, so the same run writes the same bytes.
nlohmann::json provenance();

}  // namespace ctk
