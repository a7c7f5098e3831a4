#pragma once
// The ctk-diagnosis/1 report (../shared/spec/diagnosis-report.md), one type both estimators fill:
// the marker-based diagnosis (libcalib) and the markerless refinement (librecon). What they
// share is written here once (format, provenance, the effects' common keys, what is left
// unexplained); what each measures besides goes into `extra` and each effect's `figures`.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ctk {

struct ReportedEffect {
  std::string name;
  bool accepted = false;
  double heldout_improvement_z = 0;
  nlohmann::json parameters = nlohmann::json::object(), uncertainty = nlohmann::json::object();
  std::vector<std::string> confounded_with;
  nlohmann::json figures = nlohmann::json::object();  // the estimator's own keys (errors before and after, ...)
};

struct DiagnosisReport {
  std::string mode;  // "" for the marker-based diagnosis, "markerless" for the refinement
  nlohmann::json baseline = nlohmann::json::object(), final_error = nlohmann::json::object();
  std::vector<ReportedEffect> effects;
  bool structured = false;  // residual structure no listed effect explains
  std::string unexplained_note;
  std::string criterion;                            // how an effect is accepted, in words
  nlohmann::json extra = nlohmann::json::object();  // top-level keys of the estimator's own

  /// The report as ctk-diagnosis/1, with this run's provenance.
  nlohmann::json to_json() const;
};

}  // namespace ctk
