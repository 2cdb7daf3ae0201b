// `flowplan plan`: the command, and the order of its steps (plan_*.cc);
// `flowplan plan --problems FILE` is plan_problems.cc.

#include "experiment/plan.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>

#include "core/atomic_file.h"
#include "core/error.h"
#include "experiment/commands.h"

namespace flowplan::experiment {

namespace {

/// Unless `force`: refuses `path` if it exists, pointing --out at `other`.
void RefuseExisting(const std::string& path, bool force, const std::string& other) {
  if (!force && std::filesystem::exists(path)) {
    throw Error(path + ": exists; give --force to replace it, or --out another " + other);
  }
}

}  // namespace

void CheckOutputsFree(const std::string& prefix, bool force) {
  for (const char* extension : {".json", ".h5", ".png"}) RefuseExisting(prefix + extension, force, "prefix");
}

void CheckOutputFree(const std::string& path, bool force) { RefuseExisting(path, force, "file"); }

namespace {

void RunPlan(const PlanArgs& args) {
  if (args.num_samples < 1) throw Error("-n: expected at least one plan, got " + std::to_string(args.num_samples));
  if (!(args.goal_tolerance > 0)) throw Error("--goal-tolerance: expected a positive distance");
  if (!(args.max_speed_ratio > 0)) throw Error("--max-speed-ratio: expected a positive ratio");
  if (args.batch < 1) throw Error("--batch: expected at least one plan per call, got " + std::to_string(args.batch));
  const PlanSubject subject = LoadPlanSubject(args);
  const int threads = ConfigureThreads(subject.config);
  if (!args.problems.empty()) {
    RunPlanProblems(args, subject, threads);
    return;
  }
  const PlanInputs inputs = ResolvePlanInputs(args, subject);
  const std::unique_ptr<RobotSimulator> simulator = ExecutionSimulator(args, subject);  // before any planning
  const std::string prefix = args.out.empty() ? "plan" : args.out;
  CheckOutputsFree(prefix, args.force);
  EnsureParentFolder(prefix);
  AtomicFile h5_file(prefix + ".h5");  // fails before any work if the output cannot be written

  const int64_t D = subject.trajectory.state_dim();
  planning::PlanRequest request;
  request.start = inputs.start.unsqueeze(0).expand({args.num_samples, D}).contiguous();
  request.goal = inputs.goal.unsqueeze(0).expand({args.num_samples, D}).contiguous();
  request.scene = inputs.rows;
  request.seed = static_cast<uint64_t>(args.seed);
  request.settings = subject.settings;
  const int64_t K = inputs.scene.size();
  spdlog::info("planning {} samples with {} around {} obstacle{}{} ({})", args.num_samples, subject.source, K,
               K == 1 ? "" : "s", DescribeObstacles(inputs),
               !subject.kind->network ? fmt::format("check.margin {}, {} iterations", subject.config.check.margin,
                                              subject.config.rrt_connect.max_iterations)
                                : fmt::format("guidance scale {}, splitting {}", subject.config.guidance.scale,
                                              config::EnumName(subject.config.sampler.splitting)));
  const auto started = std::chrono::steady_clock::now();
  const planning::PlanResult result = planning::PlanInChunks(*subject.planner, request, threads, args.batch);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const int64_t lost = args.num_samples - result.found.sum().item<int64_t>();
  if (lost > 0) {
    const int64_t refused = std::count(result.refused.begin(), result.refused.end(), true);
    for (size_t b = 0; b < result.failure.size(); ++b) {
      if (!result.failure[b].empty()) {
        spdlog::warn("{} of {} plans not found ({} refused: a start or goal the plan checker does not accept), each "
                     "written as the straight line from start to goal (plan {}: {})",
                     lost, args.num_samples, refused, b, result.failure[b]);
        break;
      }
    }
    if (result.failure.empty()) {
      spdlog::warn("{} of {} plans not found, each written as the straight line from start to goal", lost,
                   args.num_samples);
    }
  }

  const PlanScores scores = ScorePlans(result, subject, inputs);
  const std::vector<sim::ExecutionResult> executed =
      simulator ? ExecutePlans(result.plans, subject, inputs, *simulator, threads) : std::vector<sim::ExecutionResult>{};
  const PlanCounts counts =
      WritePlanFiles(h5_file.temp_path(), prefix, args, subject, inputs, result, scores, executed, wall, threads);
  h5_file.Commit();
  const std::string figure = args.plot ? DrawPlanFigure(prefix) : "not drawn (--no-plot)";
  if (args.plot && figure.rfind("not drawn", 0) == 0) spdlog::warn("{}.png {}; the plans and report are written", prefix, figure);
  spdlog::info("{} plans in {:.2f} s: success {}/{} (passed the plan checker: check.*){}; clear at every state "
               "with the goal within {} m: {}/{} by the TCP, {}/{} by the whole robot; wrote {}.h5, {}.json, {}",
               args.num_samples, wall, counts.success, args.num_samples,
               executed.empty() ? std::string()
                                : fmt::format(", executed {}/{} (valid, no contact, goal reached)", counts.executed,
                                              args.num_samples),
               args.goal_tolerance, counts.tcp_clear, args.num_samples, counts.arm_clear, args.num_samples, prefix,
               prefix, figure);
}

}  // namespace

Command AddPlanCommand(CLI::App& app) {
  auto args = std::make_shared<PlanArgs>();
  PlanArgs& a = *args;
  CLI::App* plan = app.add_subcommand("plan", "plan around obstacles with a trained or exported planner or RRT-Connect; "
                                              "write plans, a report and a figure (guidance.*, scene.*, execute.*)");
  plan->add_option("--ckpt", a.ckpt, "checkpoint file, or a run folder (its newest checkpoint)");
  plan->add_option("--planner", a.planner_file, "an exported planner file (instead of --ckpt)")->check(CLI::ExistingFile);
  std::string kinds;
  for (const PlannerKind& kind : PlannerKinds()) kinds += (kinds.empty() ? "" : "; ") + kind.name + ": " + kind.description;
  plan->add_option("--planner-kind", a.kind, "the planner, by name (default: learned): " + kinds);
  plan->add_flag("--rrt-connect", a.rrt_connect,
                 "--planner-kind rrt_connect: RRT-Connect (rrt_connect.*, valid by check.*) for the robot and trajectories of "
                 "--config's generate.*");
  plan->add_flag("--hybrid", a.hybrid,
                 "--planner-kind hybrid, with --ckpt or --planner: the learned planner proposes hybrid.proposals plans, the plan checker "
                 "(check.*) keeps the valid ones and returns the best by guidance cost, then length; RRT-Connect "
                 "(rrt_connect.*) plans when none is valid");
  plan->add_option("--problems", a.problems,
                   "a problem file (`flowplan problems`, `flowplan scenes import`): plan -n plans for every problem in "
                   "its own scene with one loaded planner; write PREFIX.json and PREFIX.h5")
      ->check(CLI::ExistingFile);
  plan->add_option("--limit", a.limit, "with --problems: plan the first N problems only (0: all)")
      ->check(CLI::NonNegativeNumber);
  plan->add_option("--batch", a.batch,
                   "plans per planning call (a learned planner plans a call's plans as one batch; its time per plan "
                   "is then the call's time divided by them)")
      ->capture_default_str();
  plan->add_option("--robot", a.robot,
                   "with --rrt-connect: plan for the robot of this folder (DIR/robot.yaml, written by `flowplan robot "
                   "import`; or `robot: DIR` in the config) instead of generate.*'s; generate.* still gives the horizon "
                   "and the time step")
      ->check(CLI::ExistingPath);
  plan->add_option("--config", a.overlay_path, "YAML applied over the planner's config")->check(CLI::ExistingFile);
  plan->add_option("--start", a.start, "start: J comma-separated positions (at rest) or a full state of D values");
  plan->add_option("--goal", a.goal, "goal, as --start");
  plan->add_option("--start-tcp", a.start_tcp, "start TCP point x,y,z (IK with the home posture's TCP orientation)");
  plan->add_option("--goal-tcp", a.goal_tcp, "goal TCP point x,y,z (IK with the home posture's TCP orientation)");
  plan->add_option("--scene", a.scene, "scene file (default: the config's scene section)")->check(CLI::ExistingFile);
  // One value per occurrence, so that `--sphere 0.5,0,0.2,0.1 guidance.scale=2` leaves the override alone.
  auto repeatable = [&](const std::string& name, std::vector<std::string>& values, const std::string& help) {
    plan->add_option(name, values, help)->allow_extra_args(false)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  };
  repeatable("--sphere", a.spheres, "add a sphere x,y,z,r (x,y,r in 2-D); repeatable");
  repeatable("--box", a.boxes, "add a box cx,cy,cz,lx,ly,lz[,qw,qx,qy,qz] (2-D: cx,cy,lx,ly[,angle]); repeatable");
  repeatable("--cylinder", a.cylinders, "add a cylinder cx,cy,cz,r,h[,qw,qx,qy,qz] (2-D: cx,cy,r,h[,angle]); repeatable");
  repeatable("--capsule", a.capsules, "add a capsule ax,ay,az,bx,by,bz,r (2-D: ax,ay,bx,by,r); repeatable");
  repeatable("--radius", a.radii, "set every sphere's radius (R) or sphere K's (K=R); repeatable");
  plan->add_option("-n,--num-samples", a.num_samples, "number of plans")->check(CLI::PositiveNumber);
  plan->add_option("--seed", a.seed, "seed of the plans' noise")->check(CLI::NonNegativeNumber);
  plan->add_option("--out", a.out, "output prefix: PREFIX.h5, PREFIX.json, PREFIX.png (default: plan, or plan_problems with --problems, in the working folder)");
  plan->add_flag("--execute", a.execute, "also track every plan in MuJoCo and report contacts");
  plan->add_flag("!--no-plot", a.plot, "do not draw PREFIX.png");
  plan->add_flag("--force", a.force, "replace PREFIX.h5, PREFIX.json and PREFIX.png if they exist");
  plan->add_option("--goal-tolerance", a.goal_tolerance,
                   "a plan succeeds if its last TCP is this close to the goal TCP (and it collides nowhere)");
  plan->add_option("--max-speed-ratio", a.max_speed_ratio,
                   "a plan counts as feasible (and can succeed) if the joint speeds its positions imply stay within "
                   "this many times the robot's velocity limits");
  plan->add_option("overrides", a.overrides, kOverrideHelp);
  return {plan, [args] { RunPlan(*args); }};
}

}  // namespace flowplan::experiment
