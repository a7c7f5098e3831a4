#include "ctk/core/html_report.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/output_set.hpp"

namespace ctk {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string escaped(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string base64(const std::string& bytes) {
  static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const unsigned a = static_cast<unsigned char>(bytes[i]);
    const unsigned b = i + 1 < bytes.size() ? static_cast<unsigned char>(bytes[i + 1]) : 0u;
    const unsigned c = i + 2 < bytes.size() ? static_cast<unsigned char>(bytes[i + 2]) : 0u;
    const unsigned n = (a << 16) | (b << 8) | c;
    out += digits[(n >> 18) & 63];
    out += digits[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? digits[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? digits[n & 63] : '=';
  }
  return out;
}

bool scalar(const json& v) { return v.is_primitive(); }

// Numbers as a person reads them: integers whole, others to three significant digits (the JSON
// beside the page keeps them whole).
std::string text_of(const json& v) {
  if (v.is_string()) return escaped(v.get<std::string>());
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  if (v.is_number_float()) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.3g", v.get<double>());
    return buffer;
  }
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_null()) return "&ndash;";
  if (v.is_array() && v.size() <= 16 && std::all_of(v.begin(), v.end(), scalar)) {
    std::string s;
    for (const json& x : v) s += (s.empty() ? "" : ", ") + text_of(x);
    return s;
  }
  if (v.is_array() && std::all_of(v.begin(), v.end(), scalar)) {
    std::string s;
    for (std::size_t i = 0; i < 8; ++i) s += (s.empty() ? "" : ", ") + text_of(v[i]);
    return s + ", &hellip; (" + std::to_string(v.size()) + " values)";
  }
  return "<code>" + escaped(v.dump()) + "</code>";
}

bool table_of_records(const json& v) {
  return v.is_array() && !v.empty() && std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_object(); });
}

// A list of records (per-view results) as one table: a column per key any record has, what a
// record is and its verdict first (name, index, view, status, accepted), then the others as
// they first appear (JSON objects keep their keys in alphabetical order).
void records(std::ostream& out, const json& rows) {
  std::vector<std::string> columns;
  for (const char* leading : {"name", "index", "view", "status", "accepted", "reason"})
    if (std::any_of(rows.begin(), rows.end(), [&](const json& r) { return r.contains(leading); })) columns.emplace_back(leading);
  for (const json& r : rows)
    for (auto it = r.begin(); it != r.end(); ++it)
      if (std::find(columns.begin(), columns.end(), it.key()) == columns.end()) columns.push_back(it.key());
  out << "<table class=\"records\"><tr>";
  for (const std::string& c : columns) out << "<th>" << escaped(c) << "</th>";
  out << "</tr>\n";
  for (const json& r : rows) {
    out << "<tr>";
    for (const std::string& c : columns) out << "<td>" << (r.contains(c) ? text_of(r[c]) : "") << "</td>";
    out << "</tr>\n";
  }
  out << "</table>\n";
}

void section(std::ostream& out, const std::string& name, const json& v, int depth) {
  const int level = std::min(depth + 2, 6);  // streamed: GCC 12 misreads "h" + std::string as overlapping (-Wrestrict)
  out << "<h" << level << ">" << escaped(name) << "</h" << level << ">\n";
  if (table_of_records(v)) return records(out, v);
  if (!v.is_object()) {
    out << "<p>" << text_of(v) << "</p>\n";
    return;
  }
  bool open = false;
  for (auto it = v.begin(); it != v.end(); ++it) {
    if (it->is_object() || table_of_records(*it)) continue;
    if (!open) out << "<table class=\"numbers\">\n";
    open = true;
    out << "<tr><th>" << escaped(it.key()) << "</th><td>" << text_of(*it) << "</td></tr>\n";
  }
  if (open) out << "</table>\n";
  for (auto it = v.begin(); it != v.end(); ++it)
    if (it->is_object() || table_of_records(*it)) {
      if (depth >= 3)
        out << "<p><b>" << escaped(it.key()) << "</b> <code>" << escaped(it->dump()) << "</code></p>\n";
      else
        section(out, it.key(), *it, depth + 1);
    }
}

std::string png_bytes(const fs::path& file) {
  OutputSet* set = OutputSet::active();
  const fs::path where = set ? set->current(file) : file;
  std::ifstream in(where, std::ios::binary);
  if (!in) throw std::runtime_error("HTML report: cannot read the picture " + file.string());
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

std::string html_report_text(const HtmlReport& r) {
  std::ostringstream out;
  out << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" << escaped(r.title) << "</title>\n"
      << "<style>body{font-family:sans-serif;margin:2em;max-width:80em}table{border-collapse:collapse;margin:0.5em 0}"
         "td,th{border:1px solid #ccc;padding:2px 8px;text-align:left;font-size:90%}th{background:#f2f2f2}"
         "table.records td{font-family:monospace}figure{display:inline-block;margin:0.5em;vertical-align:top}"
         "figcaption{font-size:90%;color:#444}code{font-size:85%;word-break:break-all}"
         "div.verdict{border-left:6px solid #2a6;background:#f3faf5;padding:0.6em 1em;margin:1em 0;font-size:110%}"
         "div.verdict code{font-size:95%;word-break:normal}</style></head>\n"
      << "<body>\n<h1>" << escaped(r.title) << "</h1>\n<div class=\"verdict\" id=\"verdict\"><p class=\"brief\">"
      << escaped(r.brief) << "</p>\n";
  if (!r.next.empty()) out << "<p>next: <code>" << escaped(r.next) << "</code></p>\n";
  out << "</div>\n";
  if (!r.pictures.empty()) {
    out << "<h2>pictures</h2>\n";
    for (const auto& [caption, file] : r.pictures)
      out << "<figure><img src=\"data:image/png;base64," << base64(png_bytes(file)) << "\" alt=\"" << escaped(caption)
          << "\"><figcaption>" << escaped(caption) << " (" << escaped(file.filename().string()) << ")</figcaption></figure>\n";
  }
  json body = r.report;
  json provenance;
  if (body.is_object() && body.contains("provenance")) {
    provenance = body["provenance"];
    body.erase("provenance");
  }
  section(out, "results", body, 0);
  if (!provenance.is_null()) section(out, "provenance", provenance, 0);
  // The footer says how many pictures the browser could show, and the body where the verdict ends
  // on the screen (a test reads both from the page).
  out << "<p class=\"footer\">pictures shown: <span id=\"pictures-shown\">not counted (scripts off)</span></p>\n"
      << "<script>window.addEventListener('load',function(){var i=document.images,n=0;for(var k=0;k<i.length;k++)"
         "if(i[k].complete&&i[k].naturalWidth>0)n++;var e=document.getElementById('pictures-shown');"
         "e.textContent=n+' of '+i.length;document.body.setAttribute('data-pictures-missing',String(i.length-n));"
         "var v=document.getElementById('verdict');if(v)document.body.setAttribute('data-verdict-bottom',"
         "String(Math.round(v.getBoundingClientRect().bottom)));});</script>\n"
      << "</body></html>\n";
  return out.str();
}

void write_html_report(const HtmlReport& report, const fs::path& file) { write_text_atomically(file, html_report_text(report)); }

std::string picture_caption(const fs::path& png, const fs::path& page) {
  const std::string stem = page.stem().string().substr(0, page.stem().string().find('.'));
  std::string name = png.stem().string();
  if (name.rfind(stem, 0) == 0) name = name.substr(stem.size());
  while (!name.empty() && (name.front() == '.' || name.front() == '_' || name.front() == '-')) name.erase(0, 1);
  return name.empty() ? png.filename().string() : name;
}

std::vector<fs::path> pictures_beside(const fs::path& file, const std::vector<std::string>& names) {
  std::vector<fs::path> paths;
  paths.reserve(names.size());
  for (const std::string& name : names) paths.push_back(file.parent_path() / name);
  return paths;
}

void write_run_page(const std::string& command, const std::string& brief, const json& report,
                    const std::vector<fs::path>& pictures, const fs::path& page, const std::string& next) {
  HtmlReport r{"ctk " + command, brief, report, {}, next};
  for (const fs::path& p : pictures) r.pictures.emplace_back(picture_caption(p, page), p);
  write_html_report(r, page);
}

}  // namespace ctk
