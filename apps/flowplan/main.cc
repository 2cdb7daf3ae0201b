// flowplan: generate datasets, train, evaluate and export flow-matching planners.
// Parses flags and calls one experiment::Run… function per subcommand.

#include <CLI/CLI.hpp>
#include <c10/util/Exception.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <iostream>
#include <regex>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/error.h"
#include "core/format.h"
#include "core/interrupt.h"
#include "core/logging.h"
#include "experiment/commands.h"
#include "experiment/experiment_config.h"
#include "experiment/plan.h"
#include "sim/mujoco_util.h"

namespace {

using flowplan::experiment::ExperimentConfig;

constexpr const char* kOverrideHelp =
    "config overrides key.sub=value, applied after the file (see `flowplan config keys`)";

void ParseShard(const std::string& text, flowplan::experiment::GenerateRequest& request) {
  static const std::regex pattern(R"((\d+)/(\d+))");
  std::smatch match;
  if (!std::regex_match(text, match, pattern)) {
    throw flowplan::Error("--shard: expected k/n (e.g. 0/4), got \"" + text + "\"");
  }
  try {
    request.shard_index = std::stoi(match[1].str());
    request.shard_count = std::stoi(match[2].str());
  } catch (const std::out_of_range&) {
    throw flowplan::Error("--shard: expected k/n with numbers that fit an int, got \"" + text + "\"");
  }
  if (request.shard_count < 1 || request.shard_index >= request.shard_count) {
    throw flowplan::Error("--shard: expected k/n with 0 <= k < n, got \"" + text + "\"");
  }
}

// The first word on the command line that is neither an option nor one of
// `commands`: what the user meant as the command ("" if there is none).
std::string UnknownCommand(const std::vector<std::string>& commands, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--log-level") {
      ++i;  // its value
      continue;
    }
    if (arg.empty() || arg[0] == '-') continue;
    return std::find(commands.begin(), commands.end(), arg) == commands.end() ? arg : "";
  }
  return "";
}

int Main(int argc, char** argv) {
  flowplan::SetUpLogging("info");  // the line format, also for errors found while parsing
  CLI::App app{"flowplan: flow-matching trajectory planners that stitch, from data to TorchScript"};
  app.require_subcommand(1);
  app.fallthrough();  // --log-level also after the subcommand
  app.option_defaults()->always_capture_default();
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "debug, info, warn, error or off");

  std::string config_path;
  std::vector<std::string> overrides;
  auto add_config = [&](CLI::App* command, bool required) {
    auto* option = command->add_option("--config", config_path, "experiment config (YAML)");
    option->check(CLI::ExistingFile);
    if (required) option->required();
    command->add_option("overrides", overrides, kOverrideHelp);
  };

  // generate
  auto* generate = app.add_subcommand("generate", "roll out a dataset and write it as HDF5 (generate.*)");
  add_config(generate, true);
  std::string shard = "0/1";
  std::string generate_out;
  generate->add_option("--shard", shard, "generate part k of n (episodes [kN/n, (k+1)N/n))");
  generate->add_option("--out", generate_out, "output file (default: generate.out)");

  // merge
  auto* merge = app.add_subcommand("merge", "join dataset shards written with --shard");
  std::vector<std::string> merge_inputs;
  std::string merge_out;
  merge->add_option("inputs", merge_inputs, "shard files in order")->required()->check(CLI::ExistingFile);
  merge->add_option("--out", merge_out, "merged file")->required();

  // train
  auto* train = app.add_subcommand("train", "train a planner (train.*, model.*, objective.*) or resume a run");
  add_config(train, false);
  std::string resume_dir;
  int64_t until_step = 0;
  train->add_option("--resume", resume_dir, "continue the run in this folder from its newest checkpoint");
  train->add_option("--until", until_step, "stop with a checkpoint at this step (0: train.steps)")
      ->check(CLI::NonNegativeNumber);

  // eval
  auto* eval = app.add_subcommand("eval", "evaluate a trained planner");
  eval->require_subcommand(1);
  auto* stitching = eval->add_subcommand("stitching", "stitching error on the dataset's test and training pairs");
  flowplan::experiment::EvalRequest eval_request;
  stitching->add_option("--ckpt", eval_request.ckpt, "checkpoint file, or a run folder (its newest checkpoint)")
      ->required();
  stitching->add_option("--out", eval_request.out, "JSON report (default: RUN_DIR/eval_stitching.json)");
  stitching->add_option("--config", eval_request.overlay_path, "YAML applied over the checkpoint's config")
      ->check(CLI::ExistingFile);
  stitching->add_option("overrides", eval_request.overrides, kOverrideHelp);

  // export
  auto* export_command = app.add_subcommand("export", "write the self-contained TorchScript planner");
  flowplan::experiment::EvalRequest export_request;
  export_command->add_option("--ckpt", export_request.ckpt, "checkpoint file, or a run folder")->required();
  export_command->add_option("--out", export_request.out, "output file (default: RUN_DIR/planner.pt)");
  export_command->add_option("--config", export_request.overlay_path, "YAML applied over the checkpoint's config")
      ->check(CLI::ExistingFile);
  export_command->add_option("overrides", export_request.overrides, kOverrideHelp);

  // plan
  auto* plan = app.add_subcommand("plan", "plan around obstacles with a trained or exported planner; write plans, "
                                          "a report and a figure (guidance.*, scene.*, execute.*)");
  flowplan::experiment::PlanCommand plan_command;
  plan->add_option("--ckpt", plan_command.ckpt, "checkpoint file, or a run folder (its newest checkpoint)");
  plan->add_option("--planner", plan_command.planner_file, "an exported planner file (instead of --ckpt)")
      ->check(CLI::ExistingFile);
  plan->add_flag("--rrt-connect", plan_command.rrt_connect,
                 "plan with OMPL's RRT-Connect (rrt_connect.*) for the robot of --config's dataset");
  plan->add_option("--config", plan_command.overlay_path, "YAML applied over the planner's config")
      ->check(CLI::ExistingFile);
  plan->add_option("--start", plan_command.start,
                   "start: J comma-separated positions (at rest) or a full state of D values");
  plan->add_option("--goal", plan_command.goal, "goal, as --start");
  plan->add_option("--start-tcp", plan_command.start_tcp, "start TCP point x,y,z (IK with the gripper pointing down)");
  plan->add_option("--goal-tcp", plan_command.goal_tcp, "goal TCP point x,y,z (IK with the gripper pointing down)");
  plan->add_option("--scene", plan_command.scene, "scene file (default: the config's scene section)")
      ->check(CLI::ExistingFile);
  plan->add_option("--sphere", plan_command.spheres, "add a sphere x,y,z,r (x,y,r for the particle); repeatable");
  plan->add_option("--radius", plan_command.radii, "set every sphere's radius (R) or sphere K's (K=R); repeatable");
  plan->add_option("-n,--num-samples", plan_command.num_samples, "number of plans")->check(CLI::PositiveNumber);
  plan->add_option("--seed", plan_command.seed, "seed of the plans' noise")->check(CLI::NonNegativeNumber);
  plan->add_option("--out", plan_command.out, "output prefix: PREFIX.h5, PREFIX.json, PREFIX.png (default RUN_DIR/plan)");
  plan->add_flag("--execute", plan_command.execute, "also track every plan in MuJoCo and report contacts");
  plan->add_flag("!--no-plot", plan_command.plot, "do not draw PREFIX.png");
  plan->add_option("--goal-tolerance", plan_command.goal_tolerance,
                   "a plan succeeds if its last TCP is this close to the goal TCP (and it collides nowhere)");
  plan->add_option("--max-speed-ratio", plan_command.max_speed_ratio,
                   "a plan counts as feasible (and can succeed) if the joint speeds its positions imply stay within "
                   "this many times the robot's velocity limits");
  plan->add_option("overrides", plan_command.overrides, kOverrideHelp);

  // config
  auto* config_command = app.add_subcommand("config", "show the resolved config or list every key");
  config_command->require_subcommand(1);
  auto* show = config_command->add_subcommand("show", "print the resolved config as YAML");
  add_config(show, false);
  auto* keys = config_command->add_subcommand("keys", "list every config key with its default and meaning");

  // fk
  auto* problems = app.add_subcommand("problems", "draw random Franka problems whose straight path is blocked (problems.*)");
  add_config(problems, false);
  std::string problems_out;
  problems->add_option("--out", problems_out, "YAML file of problems")->required();

  auto* fk = app.add_subcommand("fk", "print the Franka TCP position of joint angles (MuJoCo and LibTorch)");
  std::string joint_angles;
  fk->add_option("--q", joint_angles, "7 joint angles in rad, comma-separated: --q=0,-0.785,0,-2.356,0,1.571,0.785")
      ->required();

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One line and status 1, like every other error (CLI11's own would add a
    // second line and exit with its internal code).
    std::vector<std::string> commands;
    for (const CLI::App* command : app.get_subcommands([](const CLI::App*) { return true; })) {
      commands.push_back(command->get_name());
    }
    const std::string unknown = app.get_subcommands().empty() ? UnknownCommand(commands, argc, argv) : "";
    if (!unknown.empty()) {
      spdlog::error("unknown command \"{}\" (commands: {})", unknown, fmt::join(commands, ", "));
    } else {
      spdlog::error("{} (see flowplan --help)", e.what());
    }
    return 1;
  }
  flowplan::SetUpLogging(log_level);
  flowplan::InstallInterruptHandler();
  flowplan::sim::InstallMujocoHandlers();

  if (generate->parsed()) {
    flowplan::experiment::GenerateRequest request;
    ParseShard(shard, request);
    request.out = generate_out;
    flowplan::experiment::RunGenerate(flowplan::experiment::LoadExperiment(config_path, overrides), request);
  } else if (merge->parsed()) {
    flowplan::experiment::RunMerge(merge_inputs, merge_out);
  } else if (train->parsed()) {
    if (!resume_dir.empty()) {
      if (!config_path.empty()) throw flowplan::Error("train: give either --config or --resume, not both");
      flowplan::experiment::RunResume(resume_dir, overrides, until_step);
    } else {
      if (config_path.empty()) throw flowplan::Error("train: expected --config FILE or --resume RUN_DIR");
      flowplan::experiment::TrainRequest request;
      request.until_step = until_step;
      flowplan::experiment::RunTrain(flowplan::experiment::LoadExperiment(config_path, overrides), request);
    }
  } else if (stitching->parsed()) {
    flowplan::experiment::RunEvalStitching(eval_request);
  } else if (export_command->parsed()) {
    flowplan::experiment::RunExport(export_request);
  } else if (plan->parsed()) {
    if (!plan_command.ckpt.empty() && !plan_command.planner_file.empty()) {
      throw flowplan::Error("plan: give either --ckpt or --planner, not both");
    }
    flowplan::experiment::RunPlan(plan_command);
  } else if (show->parsed()) {
    std::cout << flowplan::experiment::ToYaml(flowplan::experiment::LoadExperiment(config_path, overrides));
  } else if (problems->parsed()) {
    flowplan::experiment::RunProblems(flowplan::experiment::LoadExperiment(config_path, overrides), problems_out);
  } else if (fk->parsed()) {
    flowplan::experiment::RunFrankaFk(flowplan::experiment::ParseJointAngles(joint_angles));
  } else if (keys->parsed()) {
    std::cout << flowplan::config::FormatKeys(flowplan::config::ListKeys(ExperimentConfig{}));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const flowplan::Error& e) {
    spdlog::error("{}", e.what());
  } catch (const c10::Error& e) {
    spdlog::error("LibTorch: {}", flowplan::FirstLine(e.what_without_backtrace()));
  } catch (const flowplan::InternalError& e) {
    spdlog::critical("{} (this is a bug in flowplan)", e.what());
  } catch (const std::exception& e) {
    spdlog::error("{}", flowplan::FirstLine(e.what()));
  }
  return 1;
}
