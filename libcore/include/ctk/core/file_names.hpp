#pragma once
// Files named by a pattern, in the order a person numbers them: "proj_2.tif" before
// "proj_10.tif" (digit runs compare as numbers), which a shell's sorted glob does not give.
#include <filesystem>
#include <string>
#include <vector>

namespace ctk {

/// Digit runs compare by value (then by length, so "07" after "7"), everything else by character.
bool natural_less(const std::string& a, const std::string& b);

/// The regular files in `folder` whose names match `pattern` (fnmatch: `*`, `?`, `[...]`), in
/// natural order. Throws InputError naming the folder when it cannot be listed.
std::vector<std::filesystem::path> matching_files(const std::filesystem::path& folder, const std::string& pattern);

/// A path whose last component holds a glob character (`*`, `?`, `[`).
bool is_glob(const std::string& path);

}  // namespace ctk
