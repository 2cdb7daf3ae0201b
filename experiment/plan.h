#pragma once

// `flowplan plan`: plans between a start and a goal around a scene's obstacles
// with a trained planner (a run folder, a checkpoint or an exported file),
// scores the plans (clearances, goal distance, collisions), optionally executes
// them in MuJoCo, and writes the plans (HDF5), a report (JSON) and a figure (PNG).

#include <cstdint>
#include <string>
#include <vector>

namespace flowplan::experiment {

struct PlanCommand {
  std::string ckpt;                   // --ckpt: a run folder or checkpoint file
  std::string planner_file;           // --planner: an exported planner file (instead of --ckpt)
  bool rrt_connect = false;           // --rrt-connect: OMPL's RRT-Connect on the robot of --config's dataset
  std::string overlay_path;           // --config: YAML applied over the planner's config
  std::vector<std::string> overrides;  // key=value, e.g. guidance.scale=2
  std::string start, goal;            // --start/--goal: J positions (at rest) or D state values
  std::string start_tcp, goal_tcp;    // --start-tcp/--goal-tcp: TCP points, by IK with the gripper down
  std::string scene;                  // --scene: a scene file (default: the config's scene section)
  std::vector<std::string> spheres;   // --sphere x,y,z,r (added to the scene)
  std::vector<std::string> radii;     // --radius R (every sphere) or K=R (sphere K)
  int num_samples = 64;               // -n
  int64_t seed = 0;                   // --seed
  std::string out;                    // --out: output prefix (default: RUN_DIR/plan)
  bool execute = false;               // --execute: track the plans in MuJoCo
  bool plot = true;                   // --no-plot clears it
  double goal_tolerance = 0.03;       // --goal-tolerance: success radius around the goal TCP (world units)
  double max_speed_ratio = 1.5;       // --max-speed-ratio: a feasible plan's joint speeds stay within this × the limits
};

/// @throws flowplan::Error for a bad planner file, scene, start or goal (unreachable,
///   outside the joint limits, inside an obstacle) or a scene of the wrong dimension.
void RunPlan(const PlanCommand& command);

/// Comma-separated finite numbers; `option` names them in errors.
/// @throws flowplan::Error naming the field that is empty or not a finite number.
std::vector<double> ParseNumbers(const std::string& text, const std::string& option);

}  // namespace flowplan::experiment
