// flowplan._flowplan: flowplan's C++ library for the Python package
// (python/flowplan/__init__.py). Importing it loads flowplan's native kernels
// (libflowplan_kernels registers its operators with the LibTorch that
// PyTorch runs on), so TorchScript modules that call them load in Python.

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#endif
#include <ATen/Parallel.h>
#include <torch/python.h>  // torch.Tensor <-> torch::Tensor, without copies

#include <cfenv>
#include <cmath>
#include <csignal>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "core/config.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/logging.h"
#include "experiment/commands.h"
#include "experiment/plan.h"
#include "experiment/trained_planner.h"
#include "geometry/scene_rows.h"
#include "geometry/scene.h"
#include "planning/learned_planner.h"
#include "problems/problem.h"
#include "sim/mujoco_util.h"
#include "validity/plan_check.h"

namespace py = pybind11;

namespace {

/// What a call into flowplan changes in the caller's process and gives back when it returns: the floating-point
/// mode of the calling thread (flowplan's planning and training flush denormals to zero on it, as its training does)
/// and LibTorch's intra-op thread count (the commands set it from the config's `threads`). Python code after a call
/// computes as it did before.
class KeepCallerState {
 public:
  KeepCallerState() : threads_(at::get_num_threads()) { SaveMode(); }
  ~KeepCallerState() {
    RestoreMode();
    if (at::get_num_threads() != threads_) at::set_num_threads(threads_);
  }
  KeepCallerState(const KeepCallerState&) = delete;
  KeepCallerState& operator=(const KeepCallerState&) = delete;

 private:
#if defined(__x86_64__) || defined(__i386__)
  void SaveMode() { csr_ = _mm_getcsr(); }  // MXCSR, its flush-to-zero and denormals-are-zero bits with it
  void RestoreMode() { _mm_setcsr(csr_); }
  unsigned int csr_ = 0;
#else
  void SaveMode() { std::fegetenv(&env_); }
  void RestoreMode() { std::fesetenv(&env_); }
  std::fenv_t env_;
#endif
  int threads_;
};
using KeepMode = py::call_guard<KeepCallerState>;

/// An exported planner file with flowplan's native kernels, as the bytes of a
/// TorchScript module (torch.jit.load reads them).
py::bytes NativePlanner(const std::string& path) {
  std::string bytes;
  {
    py::gil_scoped_release unlocked;
    const auto file = flowplan::planning::LearnedPlanner::Load(path);
    const auto planner = flowplan::experiment::AssembleNative(*file);
    std::ostringstream out;
    planner->module().save(out);
    bytes = out.str();
  }
  return py::bytes(bytes);
}

/// A planner as `flowplan plan` makes it (learned, RRT-Connect, the hybrid), with its plan checker.
class InProcessPlanner {
 public:
  InProcessPlanner(const std::string& kind, const std::string& planner, const std::string& ckpt,
                   const std::string& config, const std::string& robot, const std::vector<std::string>& overrides) {
    flowplan::experiment::PlanArgs args;
    args.kind = kind;
    args.planner_file = planner;
    args.ckpt = ckpt;
    args.overlay_path = config;
    args.robot = robot;
    args.overrides = overrides;
    py::gil_scoped_release unlocked;
    subject_ = flowplan::experiment::LoadPlanSubject(args);
    checker_ = std::make_unique<flowplan::validity::PlanChecker>(flowplan::experiment::MakePlanChecker(subject_));
  }

  py::dict Plan(const torch::Tensor& start, const torch::Tensor& goal, const py::dict& scene, uint64_t seed,
                std::optional<double> floor_height, const std::map<std::string, double>& held) const {
    flowplan::planning::PlanRequest request;
    request.start = start.to(torch::kFloat32).contiguous();
    request.goal = goal.to(torch::kFloat32).contiguous();
    request.scene = Rows(scene);
    request.seed = seed;
    request.settings = subject_.settings;
    request.world.floor_height = floor_height;
    request.world.held = held;
    flowplan::planning::PlanResult result;
    {
      py::gil_scoped_release unlocked;
      flowplan::planning::CheckEnds(request.start, request.goal, subject_.trajectory.state_dim(), "plan");
      result = subject_.planner->Plan(request);
    }
    const size_t B = static_cast<size_t>(result.plans.size(0));
    py::dict out;
    out["plans"] = result.plans;
    out["found"] = result.found;
    out["refused"] = result.refused.empty() ? std::vector<bool>(B, false) : result.refused;
    out["failure"] = result.failure.empty() ? std::vector<std::string>(B) : result.failure;
    out["route"] = result.route;
    std::vector<double> seconds;
    for (size_t b = 0; b < B; ++b) seconds.push_back(result.call_seconds[b] / static_cast<double>(result.call_plans[b]));
    out["seconds"] = seconds;
    return out;
  }

  std::vector<py::dict> Check(const torch::Tensor& plans, const torch::Tensor& start, const torch::Tensor& goal,
                              const py::dict& scene, const std::optional<torch::Tensor>& found,
                              std::optional<double> floor_height, const std::map<std::string, double>& held) const {
    flowplan::collision::WorldOptions world;
    world.floor_height = floor_height;
    world.held = held;
    const flowplan::geometry::SceneRows rows = Rows(scene);
    std::vector<flowplan::validity::PlanVerdict> verdicts;
    {
      py::gil_scoped_release unlocked;
      verdicts = checker_->Check(plans, start, goal, rows, found ? *found : torch::Tensor(), world);
    }
    std::vector<py::dict> out;
    for (const auto& verdict : verdicts) {
      py::dict entry;
      entry["valid"] = verdict.valid();
      entry["failure"] = flowplan::config::EnumName(verdict.failure);
      entry["reason"] = verdict.reason;
      entry["clearance"] = verdict.clearance;
      out.push_back(entry);
    }
    return out;
  }

  const std::string& kind() const { return subject_.kind->name; }
  /// Whether its network runs flowplan's native kernels (false without a network).
  bool native() const {
    return subject_.kind->network && subject_.config.sampler.network_kernels == flowplan::models::Kernels::kNative;
  }
  int64_t horizon() const { return subject_.trajectory.horizon; }
  int64_t state_dim() const { return subject_.trajectory.state_dim(); }
  int64_t num_joints() const { return subject_.robot->num_joints(); }
  double dt() const { return subject_.trajectory.dt; }
  const std::string& source() const { return subject_.source; }
  std::string config() const { return flowplan::experiment::ToYaml(subject_.config); }

 private:
  flowplan::geometry::SceneRows Rows(const py::dict& scene) const {
    flowplan::geometry::SceneRows rows;
    for (const auto& [key, value] : scene) {
      if (value.is_none()) continue;
      rows.insert(key.cast<std::string>(), value.cast<torch::Tensor>());
    }
    flowplan::geometry::CheckRows(rows, static_cast<int>(subject_.robot->workspace_dim()), "scene");
    return rows;
  }

  flowplan::experiment::PlanSubject subject_;
  std::unique_ptr<flowplan::validity::PlanChecker> checker_;
};

/// Runs `work` without the GIL, with flowplan's SIGINT/SIGTERM handlers in place of Python's (which cannot run
/// while C++ works): Ctrl-C stops the work where flowplan's commands stop, and becomes KeyboardInterrupt.
template <class Work>
auto Interruptible(Work work) {
  struct sigaction python_int {}, python_term {};
  sigaction(SIGINT, nullptr, &python_int);
  sigaction(SIGTERM, nullptr, &python_term);
  auto restore = [&] {
    sigaction(SIGINT, &python_int, nullptr);
    sigaction(SIGTERM, &python_term, nullptr);
  };
  flowplan::ClearInterrupt();
  flowplan::InstallInterruptHandler();
  try {
    py::gil_scoped_release unlocked;
    auto result = work();
    restore();
    return result;
  } catch (const flowplan::Error& e) {
    restore();
    if (!flowplan::InterruptRequested()) throw;
    flowplan::ClearInterrupt();
    PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
    throw py::error_already_set();
  } catch (...) {
    restore();
    throw;
  }
}

/// A scene's obstacles as the planners take them: kind -> (K, columns) float64 rows.
py::dict SceneDict(const flowplan::geometry::Scene& scene, int workspace_dim, const std::string& where) {
  py::dict out;
  for (const auto& entry : flowplan::geometry::Rows(scene, workspace_dim, where)) out[py::str(entry.key())] = entry.value();
  return out;
}

py::dict LoadScene(const std::string& path, int workspace_dim) {
  return SceneDict(flowplan::geometry::LoadScene(path), workspace_dim, path);
}

/// A problem file's problems, each a dict of Problem's fields (docs/planning.md, "Problem files").
py::list LoadProblems(const std::string& path) {
  const flowplan::problems::ProblemSet set = flowplan::problems::LoadProblemSet(path);
  py::list out;
  for (const flowplan::problems::Problem& p : set.problems) {
    py::dict entry;
    entry["name"] = p.name;
    entry["start"] = torch::tensor(p.start_q, torch::kFloat64);
    entry["goal"] = torch::tensor(p.goal_q, torch::kFloat64);
    const int W = p.start_tcp.size() == 2 ? 2 : 3;
    entry["scene"] = SceneDict(p.scene, W, path + ": " + p.name);
    entry["obstacle_names"] = p.obstacle_names;
    entry["floor_height"] = std::isinf(p.floor_height) ? py::none() : py::cast(p.floor_height);
    std::map<std::string, double> held;
    for (const auto& joint : p.held) held[joint.joint] = joint.value;
    entry["held"] = held;
    entry["status"] = p.status;
    entry["reason"] = p.reason;
    entry["notes"] = p.notes;
    out.append(entry);
  }
  return out;
}

/// `flowplan robot import`: the folder written, summarised as a dict (python/flowplan/__init__.py, RobotFolder).
py::dict ImportRobot(const std::string& model, const std::string& out, const std::string& srdf,
                     const std::string& package_dir, const std::string& base, const std::string& tip,
                     const std::vector<double>& tcp_offset, const std::vector<std::string>& joints,
                     const std::map<std::string, double>& hold, double overshoot, int max_spheres,
                     int64_t pair_samples, const std::vector<double>& velocity_limit, int collision_group, bool force) {
  flowplan::robotfiles::ImportOptions options;
  options.srdf = srdf;
  options.package_dir = package_dir;
  options.base = base;
  options.tip = tip;
  if (!tcp_offset.empty()) {
    if (tcp_offset.size() != 3) throw flowplan::Error("tcp_offset: expected (x, y, z)");
    options.tcp_offset = {tcp_offset[0], tcp_offset[1], tcp_offset[2]};
  }
  options.joints = joints;
  options.hold = hold;
  if (!(overshoot > 0)) throw flowplan::Error("overshoot: expected a positive distance (m)");
  if (max_spheres < 1) throw flowplan::Error("max_spheres: expected at least 1");
  if (pair_samples < 1) throw flowplan::Error("pair_samples: expected at least 1");
  options.overshoot = overshoot;
  options.max_spheres = max_spheres;
  options.pair_samples = pair_samples;
  options.velocity_limit = velocity_limit;
  options.collision_group = collision_group;
  flowplan::robotfiles::ImportResult result;
  {
    py::gil_scoped_release unlocked;
    result = flowplan::experiment::ImportRobotFolder(model, options, out, force);
  }
  const flowplan::kinematics::RobotDescription& d = result.file.robot;
  py::dict entry;
  entry["path"] = out;
  entry["name"] = d.name;
  std::vector<std::string> names;
  for (int j = 0; j < d.num_joints; ++j) names.push_back(d.JointName(j));
  entry["joints"] = names;
  entry["lower"] = torch::tensor(d.joint_lower, torch::kFloat64);
  entry["upper"] = torch::tensor(d.joint_upper, torch::kFloat64);
  entry["velocity_limit"] = torch::tensor(d.velocity_limit, torch::kFloat64);
  entry["effort_limit"] = torch::tensor(result.file.effort_limit, torch::kFloat64);
  entry["spheres"] = static_cast<int64_t>(result.file.collision.spheres.size());
  std::vector<std::tuple<std::string, std::string, std::string>> ignored;
  for (const auto& pair : result.file.collision.self_collision_ignore) {
    ignored.emplace_back(pair.links[0], pair.links[1], pair.reason);
  }
  entry["ignored_pairs"] = ignored;
  py::list cover;
  for (const flowplan::robotfiles::LinkCover& c : result.file.cover) {
    py::dict link;
    link["link"] = c.link;
    link["spheres"] = c.spheres;
    link["samples"] = c.samples;
    link["largest_uncovered"] = c.largest_uncovered;
    link["largest_outside"] = c.largest_outside;
    link["overshoot_ratio"] = c.overshoot_ratio;
    cover.append(link);
  }
  entry["cover"] = cover;
  entry["notes"] = result.notes;
  return entry;
}

}  // namespace

PYBIND11_MODULE(_flowplan, m) {
  m.doc() = "flowplan's C++ library for the Python package `flowplan` (use the package, not this module).";
  flowplan::SetUpLogging("info");  // the command line's format: "[12:00:01.234] [info] message"
  // MuJoCo's fatal errors (which cannot be thrown through its C frames) end the process with one line naming them,
  // as they do the command line's, instead of MuJoCo's default: print, then wait for Enter before exiting.
  flowplan::sim::InstallMujocoHandlers();
  static py::exception<flowplan::Error> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const flowplan::Error& e) {
      error(e.what());
    }
  });
  m.def("native_planner", &NativePlanner, py::arg("path"), KeepMode(),
        "The exported planner file at `path` assembled again with flowplan's native kernels: the bytes of its "
        "TorchScript module. Raises flowplan.Error naming the file if it is not a flowplan planner or cannot be "
        "assembled again.");
  m.def("load_scene", &LoadScene, py::arg("path"), py::arg("workspace_dim"), KeepMode(),
        "A scene file's obstacles: kind -> (K, columns) float64 rows.");
  m.def("load_problems", &LoadProblems, py::arg("path"), KeepMode(), "A problem file's problems, as dicts.");
  m.def(
      "import_scenes",
      [](const std::vector<std::string>& files, const std::string& folder, const std::string& out,
         const std::string& robot, const std::vector<std::string>& frames, const std::string& grasp,
         double grasp_margin, double limit_tolerance, bool force) {
        flowplan::experiment::SceneImport args;
        args.files = files;
        args.folder = folder;
        args.out = out;
        args.robot = robot;
        args.frames = frames;
        args.grasp = grasp;
        args.grasp_margin = grasp_margin;
        args.limit_tolerance = limit_tolerance;
        args.force = force;
        py::gil_scoped_release unlocked;
        flowplan::experiment::ImportScenes(args);
      },
      py::arg("files"), py::arg("folder"), py::arg("out"), py::arg("robot"), py::arg("frames"), py::arg("grasp"),
      py::arg("grasp_margin"), py::arg("limit_tolerance"), py::arg("force"), KeepMode(), "flowplan scenes import: writes the problem file `out`");
  m.def("import_robot", &ImportRobot, py::arg("model"), py::arg("out"), py::arg("srdf"), py::arg("package_dir"),
        py::arg("base"), py::arg("tip"), py::arg("tcp_offset"), py::arg("joints"), py::arg("hold"),
        py::arg("overshoot"), py::arg("max_spheres"), py::arg("pair_samples"), py::arg("velocity_limit"),
        py::arg("collision_group"), py::arg("force"), KeepMode(), "flowplan robot import: writes the robot folder `out`");
  m.def(
      "evaluate_stitching",
      [](const std::string& ckpt, const std::string& out, const std::string& config,
         const std::vector<std::string>& overrides) {
        flowplan::experiment::EvalArgs args;
        args.ckpt = ckpt;
        args.out = out;
        args.overlay.path = config;
        args.overlay.overrides = overrides;
        const std::string report = Interruptible([&] { return flowplan::experiment::EvaluateStitching(args); });
        return std::make_pair(report, flowplan::experiment::StitchingPlansFile(report));
      },
      py::arg("ckpt"), py::arg("out"), py::arg("config"), py::arg("overrides"), KeepMode(),
      "flowplan eval stitching: the JSON report and the plans file written");
  m.def(
      "make_problems",
      [](const std::string& out, const std::string& config, const std::vector<std::string>& overrides,
         const std::string& family, const std::string& robot, bool force) {
        flowplan::experiment::ProblemsArgs args;
        args.out = out;
        args.config.path = config;
        args.config.overrides = overrides;
        args.family = family;
        args.robot = robot;
        args.force = force;
        py::gil_scoped_release unlocked;
        flowplan::experiment::MakeProblems(args);
      },
      py::arg("out"), py::arg("config"), py::arg("overrides"), py::arg("family"), py::arg("robot"), py::arg("force"),
      KeepMode(),
      "flowplan problems: writes the problem file `out`");
  m.def(
      "render",
      [](const std::string& plans, const std::string& out, const std::string& problem, int64_t index,
         const std::string& robot, const std::string& config, const std::vector<std::string>& overrides) {
        flowplan::experiment::RenderArgs args;
        args.plans = plans;
        args.out = out;
        args.problem = problem;
        args.index = index;
        args.robot = robot;
        args.config_path = config;
        args.overrides = overrides;
        flowplan::experiment::Rendered rendered;
        {
          py::gil_scoped_release unlocked;
          rendered = flowplan::experiment::Render(args);
        }
        py::dict entry;
        entry["gif"] = rendered.gif;
        entry["png"] = rendered.png;
        entry["frames"] = rendered.frames;
        entry["shown"] = rendered.shown;
        return entry;
      },
      py::arg("plans"), py::arg("out"), py::arg("problem"), py::arg("index"), py::arg("robot"), py::arg("config"),
      py::arg("overrides"), KeepMode(), "flowplan render: writes PREFIX.gif and PREFIX.png");
  m.def("set_log_level", &flowplan::SetUpLogging, py::arg("level"),
        "What flowplan logs: debug, info (the default), warn or error.");
  m.def(
      "generate",
      [](const std::string& config, const std::vector<std::string>& overrides) {
        return Interruptible([&] { return flowplan::experiment::Generate(config, overrides); });
      },
      py::arg("config"), py::arg("overrides"), KeepMode(), "flowplan generate --config CONFIG OVERRIDES...: the file written");
  m.def(
      "train",
      [](const std::string& config, const std::vector<std::string>& overrides, const std::string& resume,
         int64_t until_step) {
        return Interruptible([&] { return flowplan::experiment::Train(config, overrides, resume, until_step); });
      },
      py::arg("config"), py::arg("overrides"), py::arg("resume"), py::arg("until_step"), KeepMode(),
      "flowplan train (--config CONFIG | --resume RUN_DIR) OVERRIDES... [--until STEP]: the run folder");
  py::class_<InProcessPlanner>(m, "InProcessPlanner")
      .def(py::init<const std::string&, const std::string&, const std::string&, const std::string&,
                    const std::string&, const std::vector<std::string>&>(),
           py::arg("kind"), py::arg("planner"), py::arg("ckpt"), py::arg("config"), py::arg("robot"),
           py::arg("overrides"), KeepMode())
      .def("plan", &InProcessPlanner::Plan, py::arg("start"), py::arg("goal"), py::arg("scene"), py::arg("seed"),
           py::arg("floor_height"), py::arg("held"), KeepMode())
      .def("check", &InProcessPlanner::Check, py::arg("plans"), py::arg("start"), py::arg("goal"), py::arg("scene"),
           py::arg("found"), py::arg("floor_height"), py::arg("held"), KeepMode())
      .def_property_readonly("kind", &InProcessPlanner::kind)
      .def_property_readonly("native", &InProcessPlanner::native)
      .def_property_readonly("horizon", &InProcessPlanner::horizon)
      .def_property_readonly("state_dim", &InProcessPlanner::state_dim)
      .def_property_readonly("num_joints", &InProcessPlanner::num_joints)
      .def_property_readonly("dt", &InProcessPlanner::dt)
      .def_property_readonly("source", &InProcessPlanner::source)
      .def_property_readonly("config", &InProcessPlanner::config);
}
