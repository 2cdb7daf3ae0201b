#pragma once

// Guidance (SPEC section 2): the costs that steer every learned planner
// around obstacles, and the guide that applies them. The computation is the
// TorchScript of this folder (guide.py, the cost classes, guidance.py); this
// file builds the modules from a config. A cost term is its class file plus
// one line in kCostTerms (guide.cc); a user may add a cost of their own as a
// TorchScript file (guidance.user_cost, docs/planning.md).

#include <torch/script.h>

#include <string>

#include "core/config.h"
#include "kinematics/robot.h"
#include "models/kernels.h"

namespace flowplan::guidance {

/// b_t, the factor on the gradient at flow time t (0 noise, 1 data).
enum class GuidanceSchedule {
  kOneMinusT,  // 1 − t (the paper's)
  kRatio,      // (1 − t)/t, with t at least 1e-3
  kRising,     // t: strongest after the last step, where the network's own pull back to the data is strongest
  kConstant,   // 1 (with sampler.guide_from: full strength from that flow time on)
};

inline const config::EnumNames<GuidanceSchedule>& EnumEntries(GuidanceSchedule) {
  static const config::EnumNames<GuidanceSchedule> names = {{GuidanceSchedule::kOneMinusT, "one_minus_t"},
                                                            {GuidanceSchedule::kRatio, "ratio"},
                                                            {GuidanceSchedule::kRising, "rising"},
                                                            {GuidanceSchedule::kConstant, "constant"}};
  return names;
}

/// The `guidance` section of an experiment config. Every number here is also a
/// per-call setting of a planner (by its key, e.g. "guidance.clip"), and so is
/// the schedule; the user cost file is compiled in.
struct GuidanceConfig {
  double scale = 1.0;  // s; 0: unguided
  GuidanceSchedule schedule = GuidanceSchedule::kOneMinusT;
  int candidates = 1;               // plans drawn per request; the one of least guidance cost is returned
  double clip = 0.0;                // cap on each term's gradient norm per state (raw units), 0: none
  double collision_weight = 0.1;    // weight of the collision cost (SPEC / the paper)
  double smoothness_weight = 1e-6;  // weight of the GP smoothness prior
  double margin = 0.05;             // world units added to the robot's spheres in the collision hinge (MPD: 0.05 m)
  double smoothness_sigma = 1.0;    // σ of the GP prior
  double joint_limit_weight = 0.0;  // weight of the joint-limit hinge
  double joint_limit_margin = 0.05;  // joint units (rad) the hinge keeps from each limit
  double joint_speed_weight = 0.0;  // weight of the joint-speed hinge
  double joint_speed_ratio = 1.0;   // share of each joint's velocity limit above which that hinge acts
  std::string user_cost;            // a TorchScript file defining cost(self, q, qd, scene); empty: none
  double user_cost_weight = 1.0;    // weight of the user cost
  // The collision cost's obstacle distances: native kernels (flowplan::shape_distance; for an arm the whole
  // hinge, kinematics included, as flowplan::arm_collision; and without a user cost the whole guidance gradient,
  // every built-in term, its cap and the normalizer, as flowplan::arm_guidance), or LibTorch's operators only
  // (what `flowplan export` writes unless told --kernels native).
  models::Kernels distance_kernels = models::Kernels::kNative;

  template <class V>
  void Visit(V& v) {
    v.Field("scale", scale, "guidance scale s (0: unguided)", config::NonNegative());
    v.Field("schedule", schedule, "b_t, the factor on the cost gradient at flow time t");
    v.Field("candidates", candidates, "plans drawn per request; the one of least guidance cost is returned",
            config::Positive());
    v.Field("clip", clip, "cap on the norm of each cost term's gradient at each state (raw units), 0 for none",
            config::NonNegative());
    v.Field("collision_weight", collision_weight, "weight of the collision cost", config::NonNegative());
    v.Field("smoothness_weight", smoothness_weight, "weight of the GP smoothness prior", config::NonNegative());
    v.Field("margin", margin, "clearance added to the robot's spheres in the collision hinge (world units)",
            config::NonNegative());
    v.Field("smoothness_sigma", smoothness_sigma, "sigma of the GP smoothness prior", config::Positive());
    v.Field("joint_limit_weight", joint_limit_weight, "weight of the joint-limit hinge (0: off)",
            config::NonNegative());
    v.Field("joint_limit_margin", joint_limit_margin, "distance the joint-limit hinge keeps from each limit",
            config::NonNegative());
    v.Field("joint_speed_weight", joint_speed_weight,
            "weight of the joint-speed hinge on the speeds between consecutive states (0: off)", config::NonNegative());
    v.Field("joint_speed_ratio", joint_speed_ratio,
            "share of each joint's velocity limit above which the joint-speed hinge acts", config::Positive());
    v.Field("user_cost", user_cost,
            "TorchScript file defining `def cost(self, q, qd, scene) -> Tensor` (docs/planning.md); empty for none");
    v.Field("user_cost_weight", user_cost_weight, "weight of the user cost", config::NonNegative());
    v.Field("distance_kernels", distance_kernels,
            "the collision cost's obstacle distances (for an arm the whole cost, and without a user cost the "
            "whole guidance gradient): native kernels (needs libflowplan_kernels where the planner runs) or "
            "portable");
  }
};

/// The guide module (guide.py) of a robot whose states x = [q, q̇] (D = 2J)
/// are sampled `dt` s apart, normalized by `normalizer` (a Normalizer module):
/// every cost term of kCostTerms, and the user's cost when config.user_cost names one.
/// @throws flowplan::Error naming guidance.user_cost if the file cannot be read or compiled.
torch::jit::Module BuildGuide(const GuidanceConfig& config, const kinematics::Robot& robot,
                              const torch::jit::Module& normalizer, double dt);

}  // namespace flowplan::guidance
