#include "planning/export.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/format.h"

namespace flowplan::planning {

torch::jit::Module BuildScriptPlanner(const Planner& planner, const ExportMetadata& metadata) {
  jit::ScriptModule module;
  planner.WriteScript(module);
  module.Attribute("format_version", c10::IntType::get(), kExportFormatVersion);
  module.Attribute("dt", c10::FloatType::get(), metadata.dt);
  module.Attribute("env", c10::StringType::get(), metadata.env);
  c10::List<std::string> labels;
  for (const auto& label : metadata.state_labels) labels.push_back(label);
  module.Attribute("state_labels", c10::ListType::ofStrings(), labels);
  module.Attribute("config", c10::StringType::get(), metadata.config_yaml);
  return module.Build("FlowplanPlanner");
}

void ExportPlanner(const Planner& planner, const ExportMetadata& metadata, const std::string& path) {
  torch::jit::Module module = BuildScriptPlanner(planner, metadata);
  AtomicFile file(path);
  try {
    module.save(file.temp_path());
  } catch (const c10::Error& e) {
    throw Error(path + ": cannot write the exported planner: " + FirstLine(e.what_without_backtrace()));
  }
  file.Commit();
}

}  // namespace flowplan::planning
