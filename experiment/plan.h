#pragma once

// `flowplan plan`: plans between a start and a goal around a scene's obstacles
// with a trained planner (a run folder, a checkpoint or an exported file) or
// RRT-Connect, scores the plans (clearance to every obstacle, goal distance,
// joint speeds), optionally executes them in MuJoCo, and writes the plans
// (HDF5), a report (JSON) and a figure (PNG). The steps live in plan_*.cc.

#include <torch/torch.h>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "experiment/experiment_config.h"
#include "experiment/robot_kinds.h"
#include "geometry/scene_rows.h"
#include "kinematics/robot.h"
#include "kinematics/trajectory_info.h"
#include "datasets/h5.h"
#include "planning/planner.h"
#include "sim/arm_execution.h"
#include "validity/plan_check.h"
#include "validity/plan_quality.h"

namespace flowplan::experiment {

struct PlanArgs {
  std::string ckpt;                    // --ckpt: a run folder or checkpoint file
  std::string planner_file;            // --planner: an exported planner file (instead of --ckpt)
  std::string kind;                    // --planner-kind: a name of PlannerKinds(); empty: learned, or a flag's
  bool rrt_connect = false;            // --rrt-connect: --planner-kind rrt_connect
  bool hybrid = false;                 // --hybrid: --planner-kind hybrid
  std::string robot;                   // --robot: for a planner without a network, a robot folder
                                       // (robotfiles/robot_folder.h)
  std::string overlay_path;            // --config: YAML applied over the planner's config
  std::vector<std::string> overrides;  // key=value, e.g. guidance.scale=2
  std::string start, goal;             // --start/--goal: J positions (at rest) or D state values
  std::string start_tcp, goal_tcp;     // --start-tcp/--goal-tcp: TCP points, by the robot's IK
  std::string scene;                   // --scene: a scene file (default: the config's scene section)
  std::vector<std::string> spheres;    // --sphere x,y,z,r (added to the scene)
  std::vector<std::string> boxes;      // --box cx,cy,cz,lx,ly,lz[,qw,qx,qy,qz]
  std::vector<std::string> cylinders;  // --cylinder cx,cy,cz,r,h[,qw,qx,qy,qz]
  std::vector<std::string> capsules;   // --capsule ax,ay,az,bx,by,bz,r
  std::vector<std::string> radii;      // --radius R (every sphere) or K=R (sphere K)
  int num_samples = 64;                // -n
  int64_t seed = 0;                    // --seed
  std::string problems;                // --problems: a problem file; plans every problem in its own scene
  int64_t limit = 0;                   // --limit: the first N problems (0: all)
  int64_t batch = 16;                  // --batch: plans per planning call
  std::string out;                     // --out: output prefix (default: ./plan, ./plan_problems)
  bool execute = false;                // --execute: track the plans in MuJoCo
  bool plot = true;                    // --no-plot clears it
  bool force = false;                  // --force: replace existing outputs
  double goal_tolerance = 0.03;        // --goal-tolerance: success radius around the goal TCP (world units)
  double max_speed_ratio = 1.5;        // --max-speed-ratio: a feasible plan's joint speeds stay within this × the limits
};

struct PlanSubject;

/// A planner `flowplan plan` runs, chosen by name (--planner-kind): one entry
/// of PlannerKinds() per planner, what it is made of and what its report
/// carries. A new planner is its own files plus one entry.
struct PlannerKind {
  std::string name;         // e.g. "learned", "rrt_connect", "hybrid"
  std::string description;  // for --help
  bool network = false;     // made from a trained network (--ckpt or --planner); else from --config and its robot
  std::vector<std::string> report_sections;  // config sections its report carries (besides check)
  // Makes subject.planner from the loaded subject (a network kind's holds the learned planner already).
  std::function<void(PlanSubject& subject)> make;
};

/// plan_subject.cc: every planner `flowplan plan` knows, in --help's order.
const std::vector<PlannerKind>& PlannerKinds();

/// The entry called `name`. @throws flowplan::Error listing the names for another.
const PlannerKind& FindPlannerKind(const std::string& name);

/// The planner a plan command runs, with what scoring and execution need.
struct PlanSubject {
  const PlannerKind* kind = nullptr;
  std::unique_ptr<planning::Planner> planner;
  ExperimentConfig config;                // resolved: the planner's, then --config, then overrides
  kinematics::TrajectoryInfo trajectory;  // what it plans
  std::shared_ptr<const kinematics::Robot> robot;
  planning::PlanSettings settings;        // the call's settings (a learned planner's)
  std::string source;                     // what was loaded, for the report
};

/// What was planned, and where.
struct PlanInputs {
  geometry::Scene scene;
  geometry::SceneRows rows;   // the scene as the planner takes it
  std::string scene_source;   // the file, or "scene (config)"
  torch::Tensor start, goal;  // (D,) raw, float32
  torch::Tensor goal_tcp;     // (W,) float64: --goal-tcp, or the goal's TCP
  collision::WorldOptions world;  // a problem's floor and held joints (unset: check.floor_height, the robot's)
};

/// The scores of N plans against K obstacles.
struct PlanScores {
  torch::Tensor tcp;            // (N, T, W) float64
  torch::Tensor tcp_clearance;  // (N, K): smallest signed distance of the TCP path's states to each obstacle
  torch::Tensor arm_clearance;  // (N, K): the same for the robot's collision spheres
  torch::Tensor goal_distance;  // (N,)
  torch::Tensor speed_ratio;    // (N,): largest joint speed the positions imply, over its limit
  std::vector<validity::PlanVerdict> verdicts;  // (N,) the plan checker's (check.*): the one success
  std::vector<validity::PlanQuality> quality;   // (N,)
};

/// plan_subject.cc: the planner of --ckpt, --planner or --rrt-connect.
/// @throws flowplan::Error for a bad file, or an override an exported file cannot take.
PlanSubject LoadPlanSubject(const PlanArgs& args);

/// plan_inputs.cc: the scene, start and goal of the command line.
/// @throws flowplan::Error for a bad scene or obstacle option, or a start or goal
///   that is unreachable, outside the joint limits or inside an obstacle.
PlanInputs ResolvePlanInputs(const PlanArgs& args, const PlanSubject& subject);

/// plan_report.cc: scores the plans (N, T, D) of `result`.
PlanScores ScorePlans(const planning::PlanResult& result, const PlanSubject& subject, const PlanInputs& inputs);

/// The plan checker of `subject` (its robot, dt, check.* and configuration check).
validity::PlanChecker MakePlanChecker(const PlanSubject& subject);

/// plan_execute.cc: with --execute, the simulator of the subject's robot (its config's robot folder, if it is not the
/// built-in Franka); nullptr without.
/// @throws flowplan::Error for a robot that is not an arm in 3-D, or that no kind of RobotKinds() simulates.
std::unique_ptr<RobotSimulator> ExecutionSimulator(const PlanArgs& args, const PlanSubject& subject);

/// plan_execute.cc: tracks every plan in MuJoCo, on `threads` workers, with the robot of `simulator` (RobotKinds():
/// made once per command) among the obstacles of `inputs`, its held joints at their values.
std::vector<sim::ExecutionResult> ExecutePlans(const torch::Tensor& plans, const PlanSubject& subject,
                                               const PlanInputs& inputs, const RobotSimulator& simulator, int threads);

/// How many plans succeeded (passed the plan checker; executed: and then
/// tracked in MuJoCo without contact to the goal), and how many were clear
/// at their states, counted by the TCP and the whole arm (the counts of the
/// sphere benchmarks, which check states only).
struct PlanCounts {
  int64_t success = 0, executed = 0, tcp_clear = 0, arm_clear = 0;
  PlanCounts& operator+=(const PlanCounts& other);
};

/// plan_report.cc: the JSON list of the plans' records, and their counts.
std::string SamplesJson(const PlanArgs& args, const planning::PlanResult& result, const PlanScores& scores,
                        const std::vector<sim::ExecutionResult>& executed, PlanCounts* counts);

/// plan_report.cc: ": spheres[0] [0.5, 0, 0.2, 0.1], … from SOURCE": every obstacle planned around, by name and
/// row, and where the scene came from; empty without obstacles.
std::string DescribeObstacles(const PlanInputs& inputs);

/// plan_report.cc: the planner's settings as report fields ("guidance": {…}, "splitting": …, "rrt_connect": {…},
/// "hybrid": {…}, as far as the planner has them, and "check": {…}), JSON objects of the config sections.
std::string SettingsJson(const PlanArgs& args, const PlanSubject& subject);

/// plan_report.cc: {"median": …, "p95": …} of the planning time per plan (s) of results.
std::string TimingJson(const std::vector<const planning::PlanResult*>& results);

/// plan_report.cc: the plans, their TCPs, the scene, start and goal (and the
/// executions) under `group` ("/" or "/problems/NAME/") of an open file.
void WritePlansH5(datasets::h5::File& file, const std::string& group, const PlanSubject& subject,
                  const PlanInputs& inputs, const planning::PlanResult& result, const PlanScores& scores,
                  const std::vector<sim::ExecutionResult>& executed);

/// plan_report.cc: the plans and executions as PREFIX.h5 (into `h5_temp`, the
/// temporary name of PREFIX.h5), the report as PREFIX.json; returns the counts.
PlanCounts WritePlanFiles(const std::string& h5_temp, const std::string& prefix, const PlanArgs& args,
                          const PlanSubject& subject, const PlanInputs& inputs, const planning::PlanResult& result,
                          const PlanScores& scores, const std::vector<sim::ExecutionResult>& executed,
                          double wall_seconds, int threads);

/// plan_problems.cc: `flowplan plan --problems FILE`: every problem of the file
/// planned by the one planner of `subject`, checked, optionally executed;
/// PREFIX.json, PREFIX.h5.
void RunPlanProblems(const PlanArgs& args, const PlanSubject& subject, int threads);

/// plan_problems.cc: the HDF5 group of problem NAME in a --problems file: "/problems/" and the name with '/'
/// and '.' made '_' (a family's "shelf/3" is /problems/shelf_3).
std::string ProblemGroup(const std::string& name);

/// plan_inputs.cc: why `state` (D,) cannot be planned from or to (past a
/// joint limit, or not valid by the plan checker in `rows` and `world`), or empty.
std::string RefusalOf(const std::string& name, const torch::Tensor& state, const PlanSubject& subject,
                      const geometry::SceneRows& rows, const collision::WorldOptions& world = {});

/// plan.cc: refuses to replace PREFIX.h5, PREFIX.json or PREFIX.png unless --force.
/// @throws flowplan::Error naming the file that exists.
void CheckOutputsFree(const std::string& prefix, bool force);

/// Unless `force`: @throws flowplan::Error naming `path` if it exists (a command's one output file, e.g.
///   `problems --out`, `scenes import --out`).
void CheckOutputFree(const std::string& path, bool force);

/// plan_report.cc: draws PREFIX.png from PREFIX.h5 with scripts/plot.py; returns
/// the figure's path, or why it was not drawn.
std::string DrawPlanFigure(const std::string& prefix);

}  // namespace flowplan::experiment
