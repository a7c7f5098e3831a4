#pragma once
// Writes a whole file or nothing: the content goes to a temporary file beside the target, which
// is renamed over it only when complete, so an interrupted run never leaves a half-written output.
#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <string_view>

namespace ctk {

/// What an existing `path` is when an output may not replace it ("a device", "a FIFO", "a socket",
/// "a folder", "not a regular file"), following symbolic links; "" for a regular file or nothing.
/// The rename that publishes an output would put a regular file in its place.
std::string not_replaceable_by_output(const std::filesystem::path& path);

/// Why `path` cannot name an output file ("names no file (...)", "a name of 300 bytes; ..."); "" when
/// it can. A name must be there and within NAME_MAX (255 bytes).
std::string not_an_output_name(const std::filesystem::path& path);

/// Calls `write` with a stream to a temporary file, then renames it to `path`.
/// Throws std::runtime_error (naming the path) when the file cannot be written, InputError when
/// `path` is not replaceable (not_replaceable_by_output) or names no file (not_an_output_name).
void write_file_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write);

/// Same for a file written by a library that takes a path (OpenImageIO, ...): `write` receives the
/// temporary path, which must carry the same extension so the library picks the right format.
void write_path_atomically(const std::filesystem::path& path, const std::function<void(const std::filesystem::path&)>& write);

void write_text_atomically(const std::filesystem::path& path, std::string_view text);

}  // namespace ctk
