// `flowplan plan --problems FILE`: every problem of a problem file (start and
// goal configurations and their scene) planned by one loaded planner, each
// plan checked (and optionally executed), in one report:
//
//   PREFIX.json  {"planner", "problems_file", "num_problems", "planned", "refused", "num_samples" (per problem),
//                 "success_rate" (of every plan asked for; a refused problem's plans count as failures),
//                 "problems_solved" (how many have at least one success), "problems_solved_rate" (their
//                 share), "success_rate_executed",
//                 "planning_time_s" {median, p95, plans, per}, "problems": [{"name", "status": "planned" |
//                 "refused", "reason", "group" (its HDF5 group), "success_rate", "samples": [...]}]}
//   PREFIX.h5    ProblemGroup(NAME)/{plans, tcp, scene/…, start, goal, goal_tcp, executed/…} per planned problem

#include <spdlog/spdlog.h>

#include <chrono>
#include <map>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/format.h"
#include "core/interrupt.h"
#include "core/random.h"
#include "experiment/command_line.h"
#include "experiment/plan.h"
#include "problems/problem.h"

namespace flowplan::experiment {
namespace {

/// The inputs of one problem: its scene, and its configurations at rest as states.
PlanInputs ProblemInputs(const problems::Problem& problem, const PlanSubject& subject, const std::string& where) {
  const int64_t J = subject.robot->num_joints(), D = subject.trajectory.state_dim();
  const int W = static_cast<int>(subject.robot->workspace_dim());
  auto state = [&](const std::vector<double>& q, const char* key) {
    if (static_cast<int64_t>(q.size()) != J) {
      throw Error(where + ": " + key + ": expected " + std::to_string(J) + " joint positions for this planner's robot, got " +
                  std::to_string(q.size()));
    }
    torch::Tensor s = torch::zeros({D}, torch::kFloat64);
    s.slice(0, 0, J) = torch::tensor(q, torch::kFloat64);
    return s.to(torch::kFloat32);
  };
  PlanInputs inputs;
  inputs.scene = problem.scene;
  inputs.scene_source = where;
  inputs.rows = geometry::Rows(inputs.scene, W, where + ": scene");
  inputs.world = problem.World();
  if (problem.refused() && problem.start_q.empty()) return inputs;  // a pair the import could not read
  inputs.start = state(problem.start_q, "start_q");
  inputs.goal = state(problem.goal_q, "goal_q");
  inputs.goal_tcp = subject.robot->Tcp(inputs.goal.slice(0, 0, J).view({1, J}).to(torch::kFloat64)).view({W});
  return inputs;
}

}  // namespace

std::string ProblemGroup(const std::string& name) {
  std::string out = name;
  for (char& c : out) {
    if (c == '/' || c == '.') c = '_';
  }
  return "/problems/" + out;
}

void RunPlanProblems(const PlanArgs& args, const PlanSubject& subject, int threads) {
  const bool single = !args.start.empty() || !args.goal.empty() || !args.start_tcp.empty() || !args.goal_tcp.empty() ||
                      !args.scene.empty() || !args.spheres.empty() || !args.boxes.empty() || !args.cylinders.empty() ||
                      !args.capsules.empty() || !args.radii.empty();
  if (single) {
    throw Error("--problems: every problem gives its own start, goal and scene; leave out --start, --goal, "
                "--start-tcp, --goal-tcp, --scene and the obstacle options");
  }
  const std::unique_ptr<RobotSimulator> simulator = ExecutionSimulator(args, subject);  // before any planning
  const problems::ProblemSet set = problems::LoadProblemSet(args.problems);
  const int64_t count = args.limit > 0 ? std::min<int64_t>(args.limit, static_cast<int64_t>(set.problems.size()))
                                       : static_cast<int64_t>(set.problems.size());
  const std::string prefix = args.out.empty() ? "plan_problems" : args.out;
  CheckOutputsFree(prefix, args.force);
  EnsureParentFolder(prefix);
  AtomicFile h5_file(prefix + ".h5");
  // Every problem's inputs are read before any planning, so that a bad entry fails at once.
  std::vector<PlanInputs> inputs;
  std::map<std::string, std::string> groups;  // HDF5 group -> the problem that has it
  for (int64_t p = 0; p < count; ++p) {
    const problems::Problem& problem = set.problems[static_cast<size_t>(p)];
    const std::string where = args.problems + ": problems[" + std::to_string(p) + "]";
    if (problem.name.empty()) throw Error(where + ".name: expected a name");
    const auto [at, fresh] = groups.emplace(ProblemGroup(problem.name), problem.name);
    if (!fresh) {
      throw Error(where + ".name: \"" + problem.name + "\" would share its report entry with \"" + at->second +
                  "\"; give every problem its own name");
    }
    inputs.push_back(ProblemInputs(problem, subject, args.problems + ": problems[" + std::to_string(p) + "] (" +
                                                         problem.name + ")"));
  }
  auto file = datasets::h5::File::Create(h5_file.temp_path());
  const kinematics::TrajectoryInfo& info = subject.trajectory;
  file.SetAttribute("/", "env", info.env);
  file.SetAttribute("/", "dt", info.dt);
  file.SetAttribute("/", "state_labels", Join(info.state_labels, ","));
  file.SetAttribute("/", "robot", kinematics::RobotToYaml(info.robot));
  file.SetAttribute("/", "planner", subject.source);
  file.SetAttribute("/", "problems_file", args.problems);
  file.SetAttribute("/", "seed", args.seed);
  file.CreateGroup("/problems");

  const int64_t D = info.state_dim(), N = args.num_samples;
  PlanCounts total;
  int64_t planned = 0, solved = 0;
  std::vector<planning::PlanResult> results;
  results.reserve(static_cast<size_t>(count));
  std::string entries;
  double planning_wall = 0.0;  // s, the planning calls alone (checks and execution excluded), as in a single report
  for (int64_t p = 0; p < count; ++p) {
    ThrowIfInterrupted();
    const problems::Problem& problem = set.problems[static_cast<size_t>(p)];
    const PlanInputs& in = inputs[static_cast<size_t>(p)];
    // Refused by whoever made the problem (the import), or by this planner's check.
    std::string refusal = problem.refused() ? problem.reason : "";
    if (refusal.empty()) refusal = RefusalOf("start", in.start, subject, in.rows, in.world);
    if (refusal.empty()) refusal = RefusalOf("goal", in.goal, subject, in.rows, in.world);
    std::string entry = "{\"name\": " + JsonString(problem.name);
    if (!refusal.empty()) {
      spdlog::info("problem {}/{} {}: refused: {}", p + 1, count, problem.name, refusal);
      entries += std::string(entries.empty() ? "" : ",\n  ") + entry + ", \"status\": \"refused\", \"reason\": " +
                 JsonString(refusal) + ", \"success_rate\": 0, \"samples\": []}";
      continue;
    }
    planning::PlanRequest request;
    request.start = in.start.unsqueeze(0).expand({N, D}).contiguous();
    request.goal = in.goal.unsqueeze(0).expand({N, D}).contiguous();
    request.scene = in.rows;
    request.seed = StreamSeed(static_cast<uint64_t>(args.seed), static_cast<uint64_t>(p));
    request.settings = subject.settings;
    request.world = in.world;
    const auto began = std::chrono::steady_clock::now();
    results.push_back(planning::PlanInChunks(*subject.planner, request, threads, args.batch));
    planning_wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
    const planning::PlanResult& result = results.back();
    const PlanScores scores = ScorePlans(result, subject, in);
    const std::vector<sim::ExecutionResult> executed =
        simulator ? ExecutePlans(result.plans, subject, in, *simulator, threads) : std::vector<sim::ExecutionResult>{};
    const std::string group = ProblemGroup(problem.name);
    file.CreateGroup(group);
    WritePlansH5(file, group + "/", subject, in, result, scores, executed);
    PlanCounts counts;
    const std::string samples = SamplesJson(args, result, scores, executed, &counts);
    total += counts;
    ++planned;
    solved += counts.success > 0;
    double seconds = 0.0;  // the planning time of the problem's plans, per plan
    for (size_t i = 0; i < result.call_seconds.size(); ++i) seconds += result.call_seconds[i] / result.call_plans[i];
    spdlog::info("problem {}/{} {}: success {}/{}{}, {:.3g} s per plan (mean)", p + 1, count, problem.name,
                 counts.success, N, executed.empty() ? std::string() : fmt::format(", executed {}/{}", counts.executed, N),
                 seconds / static_cast<double>(N));
    entries += std::string(entries.empty() ? "" : ",\n  ") + entry +
               ", \"status\": \"planned\", \"reason\": \"\", \"group\": " + JsonString(group) + ", \"success_rate\": " +
               JsonNumber(static_cast<double>(counts.success) / static_cast<double>(N)) +
               (executed.empty() ? std::string()
                                 : ", \"success_rate_executed\": " +
                                       JsonNumber(static_cast<double>(counts.executed) / static_cast<double>(N))) +
               ",\n   \"samples\": " + samples + "}";
    // The report needs only the plans' timings; the plans are written and not kept (-n 64 over 700 problems would
    // keep 160 MB).
    results.back().plans = torch::Tensor();
    results.back().found = torch::Tensor();
  }
  file.Close();
  std::vector<const planning::PlanResult*> timed;
  for (const auto& r : results) timed.push_back(&r);
  const double asked = static_cast<double>(count * N);
  auto rate = [&](int64_t k) { return JsonNumber(count > 0 ? static_cast<double>(k) / asked : 0.0); };
  const std::string json =
      "{\"planner\": " + JsonString(subject.source) + ", \"env\": " + JsonString(info.env) +
      ", \"problems_file\": " + JsonString(args.problems) + ", \"num_problems\": " + std::to_string(count) +
      ", \"planned\": " + std::to_string(planned) + ", \"refused\": " + std::to_string(count - planned) +
      ", \"num_samples\": " + std::to_string(N) + ", \"seed\": " + std::to_string(args.seed) +
      ", \"goal_tolerance\": " + JsonNumber(args.goal_tolerance) +
      ", \"max_speed_ratio\": " + JsonNumber(args.max_speed_ratio) +
      ",\n " + SettingsJson(args, subject) +
      ",\n \"success_rate\": " + rate(total.success) +
      ", \"problems_solved\": " + std::to_string(solved) +
      ", \"problems_solved_rate\": " + JsonNumber(count > 0 ? static_cast<double>(solved) / static_cast<double>(count) : 0.0) +
      (args.execute ? ", \"success_rate_executed\": " + rate(total.executed) : std::string()) +
      ", \"tcp_clear_rate\": " + rate(total.tcp_clear) + ", \"arm_clear_rate\": " + rate(total.arm_clear) +
      ",\n \"planning_time_s\": " + TimingJson(timed) + ", \"wall_time_s\": " + JsonNumber(planning_wall) +
      ", \"threads\": " + std::to_string(threads) + ",\n \"problems\": [\n  " + entries + "]}\n";
  h5_file.Commit();
  WriteFileAtomically(prefix + ".json", json);
  spdlog::info("{} problems ({} refused), {} plans each: success {}/{} plans{}, {}/{} problems solved; wrote {}.json, "
               "{}.h5",
               count, count - planned, N, total.success, count * N,
               args.execute ? fmt::format(", executed {}/{}", total.executed, count * N) : std::string(), solved, count,
               prefix, prefix);
}

}  // namespace flowplan::experiment
