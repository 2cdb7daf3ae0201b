#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "classical/rrt_connect.h"
#include "core/config.h"
#include "datasets/generate_config.h"
#include "datasets/trajectory_loader.h"
#include "distributed/distributed_config.h"
#include "eval/stitching.h"
#include "geometry/scene.h"
#include "guidance/guide.h"
#include "hybrid/hybrid_planner.h"
#include "models/model_config.h"
#include "objectives/objective.h"
#include "planning/sampler_config.h"
#include "problems/blocked_problems.h"
#include "render/arm_renderer.h"
#include "sim/franka_execution.h"
#include "trainer/trainer_config.h"
#include "validity/plan_check.h"

namespace flowplan::experiment {

/// A whole experiment: one YAML file drives generate, train, eval and export.
struct ExperimentConfig {
  int64_t seed = 0;                  // every random draw of the run derives from it
  int threads = 0;                   // CPU threads (0: all cores); does not change results
  std::string device = "cpu";        // cpu, cuda, cuda:N: where networks train and sample
  std::string run_dir = "runs/particle_cross";
  std::string robot;                 // a robot folder (`flowplan robot import`); empty: the data task's own robot
  datasets::GenerateConfig generate;
  datasets::DataConfig data;
  models::ModelConfig model;
  objectives::ObjectiveConfig objective;
  trainer::TrainerConfig train;
  planning::SamplerConfig sampler;
  eval::EvalConfig eval;
  guidance::GuidanceConfig guidance;
  geometry::Scene scene;
  sim::ExecutionConfig execute;
  classical::RrtConnectConfig rrt_connect;
  validity::CheckConfig check;
  hybrid::HybridConfig hybrid;
  render::RenderConfig render;
  distributed::DistributedConfig distributed;
  problems::BlockedProblemsConfig problems;

  template <class V>
  void Visit(V& v) {
    v.Field("seed", seed, "base seed of every random draw", config::NonNegative());
    v.Field("threads", threads, "CPU threads, 0 for all cores (results do not depend on it)",
            config::InRange(0, 1024));
    v.Field("device", device,
            "where networks train and plan: cpu, cuda or cuda:N (random draws stay on the CPU; guidance, "
            "simulation and the VAE planner run on the CPU)");
    v.Field("run_dir", run_dir, "folder of the training run (config, metrics, checkpoints, planner)");
    v.Field("robot", robot,
            "a robot folder (`flowplan robot import`): the robot generate.dataset robot_joint simulates and `plan "
            "--rrt-connect` plans for (as --robot); empty: the built-in robot of generate.*");
    v.Field("generate", generate, "dataset generation");
    v.Field("data", data, "training data");
    v.Field("model", model, "velocity network");
    v.Field("objective", objective, "training objective and conditioning");
    v.Field("train", train, "optimization");
    v.Field("sampler", sampler, "sampling");
    v.Field("eval", eval, "evaluation");
    v.Field("guidance", guidance, "guidance around obstacles (planning)");
    v.Field("scene", scene, "obstacles of `flowplan plan` when no --scene is given (geometry/scene.h)");
    v.Field("execute", execute, "tracking of plans in MuJoCo (`flowplan plan --execute`)");
    v.Field("rrt_connect", rrt_connect,
            "the classical reference planner (`flowplan plan --rrt-connect`, for the robot and trajectories of generate.*)");
    v.Field("check", check,
            "what a valid plan is: every plan a report calls a success passed this check (validity/plan_check.h)");
    v.Field("hybrid", hybrid, "the hybrid planner (`flowplan plan --hybrid`): learned proposals, RRT-Connect fallback");
    v.Field("render", render, "pictures of plans (`flowplan render`): size and camera");
    v.Field("problems", problems, "random planning problems with blocked straight paths (`flowplan problems`)");
    v.Field("distributed", distributed,
            "data-parallel training when launched as several processes (torchrun or Slurm environment)");
  }
};

/// Defaults, then `path` (if non-empty), then the key=value overrides.
ExperimentConfig LoadExperiment(const std::string& path, const std::vector<std::string>& overrides);

/// A config from YAML text (a checkpoint's or a run's), then an optional overlay
/// file, then overrides. `source` names the text in errors.
ExperimentConfig LoadExperimentText(const std::string& yaml, const std::string& source,
                                    const std::string& overlay_path, const std::vector<std::string>& overrides);

/// The resolved config as YAML; it reads back to the same config (an unset number, NaN, is left out).
std::string ToYaml(const ExperimentConfig& config);

/// The resolved config as stored in a dataset: without `threads` and
/// `generate.out`, which do not change the data, so that any thread count and
/// any output path (a shard's too) write the same bytes.
std::string DatasetConfigYaml(const ExperimentConfig& config);

}  // namespace flowplan::experiment
