#pragma once
// One self-contained HTML page per run, to open in any browser and pass on: what the run did in a
// line, its numbers and per-view tables rendered from its JSON report, its pictures embedded (PNG
// as data URIs, so the page needs no file beside it), and the build and command line that made it.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace ctk {

struct HtmlReport {
  std::string title;  // "ctk calibrate"
  std::string brief;  // the run's one-line summary: what was found, how sure (the verdict on top)
  /// Rendered section by section: top-level numbers and texts in one table, each object as a
  /// section, lists of objects (per-view records) as tables, `provenance` last.
  nlohmann::json report;
  /// Caption and PNG file. A file still waiting in the active OutputSet is read where it waits.
  std::vector<std::pair<std::string, std::filesystem::path>> pictures;
  std::string next;  // the command to run next, shown under the verdict ("" for none)
};

/// The page as text (the pictures read and encoded). Throws std::runtime_error naming a picture
/// that cannot be read.
std::string html_report_text(const HtmlReport& report);

/// Written atomically (waiting in the active OutputSet like every output).
void write_html_report(const HtmlReport& report, const std::filesystem::path& file);

/// "calibrated.residuals.png" beside the page "calibrated.report.html" -> "residuals": the part of
/// a picture's name after the page's stem (up to its first dot) names what it shows.
std::string picture_caption(const std::filesystem::path& png, const std::filesystem::path& page);

/// The pictures a run wrote beside `file` (its stem, or any file in their folder), named as the
/// picture writers return them, as paths.
std::vector<std::filesystem::path> pictures_beside(const std::filesystem::path& file, const std::vector<std::string>& names);

/// A run's page (`command` as in "ctk calibrate"), each picture captioned by its name, written to `page`.
void write_run_page(const std::string& command, const std::string& brief, const nlohmann::json& report,
                    const std::vector<std::filesystem::path>& pictures, const std::filesystem::path& page,
                    const std::string& next = "");

}  // namespace ctk
