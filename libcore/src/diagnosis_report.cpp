#include "ctk/core/diagnosis_report.hpp"

#include "ctk/core/provenance.hpp"

namespace ctk {

nlohmann::json DiagnosisReport::to_json() const {
  nlohmann::json effects_json = nlohmann::json::array();
  for (const ReportedEffect& e : effects) {
    nlohmann::json j = e.figures;
    j["name"] = e.name;
    j["accepted"] = e.accepted;
    j["heldout_improvement_z"] = e.heldout_improvement_z;
    j["parameters"] = e.parameters;
    j["uncertainty"] = e.uncertainty;
    j["confounded_with"] = e.confounded_with;
    effects_json.push_back(std::move(j));
  }
  nlohmann::json r = extra;
  r["format"] = "ctk-diagnosis/1";
  r["provenance"] = provenance();
  if (!mode.empty()) r["mode"] = mode;
  r["baseline"] = baseline;
  r["final"] = final_error;
  r["effects"] = effects_json;
  r["unexplained"] = {{"structured", structured}, {"note", unexplained_note}};
  r["criterion"] = criterion;
  return r;
}

}  // namespace ctk
