#pragma once

// The subcommands of `flowplan`, one file each. apps/flowplan/main.cc adds
// them all (AddCommands), parses, and runs the one the command line chose.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "experiment/command_line.h"
#include "robotfiles/urdf_import.h"

namespace flowplan::experiment {

Command AddGenerateCommand(CLI::App& app);  // generate.cc: roll out a dataset
Command AddMergeCommand(CLI::App& app);     // generate.cc: join dataset shards
Command AddTrainCommand(CLI::App& app);     // train.cc: train or resume a run
Command AddEvalCommand(CLI::App& app);      // eval.cc: stitching error of a trained planner
Command AddExportCommand(CLI::App& app);    // export.cc: the TorchScript planner
Command AddPlanCommand(CLI::App& app);      // plan.cc: plan around obstacles, score, execute
Command AddProblemsCommand(CLI::App& app);  // problems.cc: random blocked planning problems
Command AddScenesCommand(CLI::App& app);    // scenes.cc: import MoveIt scenes and requests
Command AddConfigCommand(CLI::App& app);    // config.cc: the resolved config, every key
Command AddRenderCommand(CLI::App& app);    // render.cc: a plan executed in MuJoCo, as a video and a picture
Command AddRobotCommand(CLI::App& app);     // robot.cc: robots as data, imported from a URDF
Command AddFkCommand(CLI::App& app);        // fk.cc: the Franka's TCP through MuJoCo and the kinematics

/// Every subcommand, in the order `flowplan --help` lists them.
std::vector<Command> AddCommands(CLI::App& app);

// The work of seven commands as functions (the Python package calls them).

/// `flowplan generate --config CONFIG OVERRIDES...`: the data set of the config
/// (every episode, one file). Returns the file written (generate.out).
/// @throws flowplan::Error as the command.
std::string Generate(const std::string& config_path, const std::vector<std::string>& overrides);

/// `flowplan scenes import`'s arguments.
struct SceneImport {
  std::vector<std::string> files;  // SCENE REQUEST pairs
  std::string folder;              // --dir: a folder of sceneNNNN.yaml / requestNNNN.yaml pairs
  std::string out;                 // --out: the problem file
  std::string scenes_dir;          // --scenes-dir: also each problem's scene file (empty: none)
  std::vector<std::string> frames; // --frame: the robot's base frame ids (empty: the robot's own)
  std::string grasp = "touching-tcp";
  double grasp_margin = 0.01;      // m
  double limit_tolerance = 0.002;  // rad
  std::string robot;               // --robot: a robot folder (empty: the built-in Franka)
  bool force = false;              // --force: replace --out (and the --scenes-dir files) if they exist
};

/// `flowplan scenes import`: MoveIt scenes and requests into the problem file
/// args.out; a pair that cannot be planned is a refused problem, a file that is
/// not a MoveIt file an error naming it. @throws flowplan::Error as the command.
void ImportScenes(const SceneImport& args);

/// `flowplan robot import MODEL --out DIR`: the robot folder DIR (DIR/meshes/,
/// then DIR/robot.yaml) from a URDF (.urdf) or an MJCF (.xml), each decision of
/// the import and each link's sphere cover logged in one line. Returns what was
/// written. @throws flowplan::Error if DIR/robot.yaml exists and not `force`,
/// and as robotfiles::ImportRobot (naming the file and element at fault).
robotfiles::ImportResult ImportRobotFolder(const std::string& model, const robotfiles::ImportOptions& options,
                                           const std::string& out, bool force);

/// `flowplan render`'s arguments.
struct RenderArgs {
  std::string plans;                   // the plan file (HDF5)
  std::string problem;                 // --problem: a problem of a --problems file
  int64_t index = 0;                   // --index: which plan
  std::string out;                     // --out: PREFIX.gif and PREFIX.png (empty: the plan file's, problem, index)
  std::string config_path;             // --config: render.* and execute.*
  std::string robot;                   // --robot: the robot folder of the plans, to execute them
  std::vector<std::string> overrides;  // key=value
};

/// What `flowplan render` wrote.
struct Rendered {
  std::string gif, png;  // the video (one frame a state) and the plan at four states
  int64_t frames = 0;
  std::string shown;     // what the video shows: the plan executed in MuJoCo (contacts, goal distance) or as planned
};

/// `flowplan render PLANS`: one plan of a plan file drawn among its scene's
/// shapes, executed in MuJoCo first for the built-in Franka and, given its
/// folder, any robot. @throws flowplan::Error naming the file, problem, index
/// or setting at fault.
Rendered Render(const RenderArgs& args);

/// `flowplan problems`'s arguments.
struct ProblemsArgs {
  ConfigArgs config;   // --config and key=value: problems.*, seed, threads, robot
  std::string out;     // --out: the problem file
  std::string family;  // --family: a procedural scene family (empty: blocked problems)
  std::string robot;   // --robot: a robot folder to draw the problems for (empty: config.robot, or the Franka)
  bool force = false;  // --force: replace --out if it exists
};

/// `flowplan problems`: random planning problems written to args.out, either
/// spheres blocking the straight TCP path (problems.*) or a scene family's.
/// @throws flowplan::Error naming the setting or folder at fault.
void MakeProblems(const ProblemsArgs& args);

/// `flowplan eval stitching`'s arguments.
struct EvalArgs {
  std::string ckpt;    // --ckpt: a checkpoint file, or a run folder (its newest checkpoint)
  ConfigArgs overlay;  // --config and key=value: applied over the checkpoint's config
  std::string out;     // --out: the JSON report (empty: RUN_DIR/eval_stitching.json)
};

/// `flowplan eval stitching`: the unguided planner's stitching error on the
/// data set's test and training pairs, written as the JSON report, whose path
/// it returns, and its plans beside it (StitchingPlansFile of that path).
/// @throws flowplan::Error naming the checkpoint, data set or setting at fault.
std::string EvaluateStitching(const EvalArgs& args);

/// The HDF5 file of the plans beside the stitching report `report` (REPORT without its extension, .plans.h5).
std::string StitchingPlansFile(const std::string& report);

/// `flowplan train --config CONFIG OVERRIDES... [--until STEP]`, or with
/// `resume_dir` set `flowplan train --resume RESUME_DIR OVERRIDES...`. Returns
/// the run folder. Ctrl-C (SIGINT, SIGTERM: the caller's handlers must let
/// core/interrupt.h's flag be raised) stops it with a checkpoint and an error
/// that says how to resume.
std::string Train(const std::string& config_path, const std::vector<std::string>& overrides,
                  const std::string& resume_dir, int64_t until_step);

}  // namespace flowplan::experiment
