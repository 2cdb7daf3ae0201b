#include "experiment/commands.h"

namespace flowplan::experiment {

std::vector<Command> AddCommands(CLI::App& app) {
  return {AddGenerateCommand(app), AddMergeCommand(app),   AddTrainCommand(app),  AddEvalCommand(app),
          AddExportCommand(app),   AddPlanCommand(app),    AddProblemsCommand(app), AddScenesCommand(app),
          AddRobotCommand(app),    AddRenderCommand(app),  AddConfigCommand(app), AddFkCommand(app)};
}

}  // namespace flowplan::experiment
