#pragma once

// flowplan's one notion of a valid configuration and a valid motion, for a
// robot's collision body (collision/body_model.h) in a world
// (collision/world.h). The plan checker, RRT-Connect, the hybrid planner,
// the problem importers and the start and goal checks all ask it.
//
// A configuration is valid when
//  - every collision sphere keeps `margin` from every obstacle and from the
//    floor (links the robot marks floor_exempt aside), and
//  - no two spheres of a link pair the robot checks overlap (self-collision).
// Joint limits are the caller's: a search samples inside them, a plan
// checker reads them from the plan.
//
// A motion, the straight joint-space segment from q_a to q_b, is valid when
// every configuration on it is, certified by conservative advancement: along
// the segment a point fixed on a link moves at most Σ_j travel_j |Δq_j|
// (BodyModel::sphere_travel), and a signed distance changes no faster than the
// points it is measured between, so a distance that is d_a and d_b at the ends
// stays at least (d_a + d_b − travel) / 2 on the whole segment. A segment for
// which that bound is below the margin for some sphere (or pair of spheres) is
// halved, and its halves are checked the same way, until every piece is
// certified, a configuration that is not valid is found, or a piece's spheres
// move less than `resolution` (its ends valid: it may come closer than the
// margin by at most resolution / 2, which is accepted).
//
// Link bounding spheres screen the work: a link far from an obstacle (or the
// floor, or another link) is not looked at sphere by sphere. Plain C++ on
// float64, no allocation once a call's workspace has grown; const methods are
// safe to call from several threads (each call has its own workspace).

#include <memory>
#include <string>
#include <vector>

#include "collision/body_model.h"
#include "collision/world.h"

namespace flowplan::collision {

struct CheckSettings {
  double margin = 0.0;        // world units every sphere keeps from every obstacle and the floor
  double resolution = 0.001;  // world units: motion checks stop halving below this sphere travel
};

/// What makes a configuration invalid: the first contact found.
struct Contact {
  enum class Kind { kNone, kObstacle, kFloor, kSelf };
  Kind kind = Kind::kNone;
  int sphere = -1;       // the body's sphere (BodyModel numbering)
  int other = -1;        // the obstacle (kObstacle) or the other sphere (kSelf)
  double distance = 0.0; // its signed distance (obstacle, floor: clearance; self: gap between the spheres)
  bool found() const { return kind != Kind::kNone; }
};

/// The verdict on one motion.
struct MotionVerdict {
  bool valid = true;
  double fraction = 0.0;     // where along the segment the contact lies (0 at q_a, 1 at q_b)
  Contact contact;           // the contact there, when not valid
  int64_t checks = 0;        // configurations checked between the ends
};

/// The verdict on a path of states: the first state that is not valid, or
/// else the first motion between consecutive states that is not.
struct PathVerdict {
  int state = -1;              // the first state that is not valid (-1: every state is)
  Contact state_contact;       // its contact
  int motion = -1;             // the first motion t -> t + 1 that is not valid, every state being (-1: none)
  MotionVerdict motion_verdict;
  int64_t checks = 0;          // configurations checked between the states
  bool valid() const { return state < 0 && motion < 0; }
};

class Checker {
 public:
  /// @throws flowplan::Error if the world's dimension is not the body's.
  Checker(std::shared_ptr<const BodyModel> body, std::shared_ptr<const World> world, CheckSettings settings);

  const BodyModel& body() const { return *body_; }
  const World& world() const { return *world_; }
  const CheckSettings& settings() const { return settings_; }

  /// Whether configuration q (J) is valid (a configuration holding NaN is not).
  bool Valid(const double* q) const;

  /// The first contact that makes q (J) invalid; kind kNone when it is valid.
  Contact FirstContact(const double* q) const;

  /// The smallest signed distance of any sphere to any obstacle (the floor
  /// aside), exact; +inf without obstacles.
  double Clearance(const double* q) const;

  /// Whether the motion from q_a to q_b (J) is valid, its ends taken as
  /// valid (check them with Valid first).
  MotionVerdict CheckMotion(const double* qa, const double* qb) const;
  bool MotionValid(const double* qa, const double* qb) const { return CheckMotion(qa, qb).valid; }

  /// The n states q (n × J) judged as FirstContact judges each, then the motions between consecutive states as
  /// CheckMotion does, in order, up to the first that is not valid: the same verdicts, each state placed once.
  /// @throws flowplan::InternalError for n < 0.
  PathVerdict CheckPath(const double* q, int n) const;

  /// One line naming what touches what: "sphere 12 (link5_c0) is -0.003 from obstacle 4 (shelf_top)",
  /// "sphere 3 (hand_c0) is 0.01 below the floor", "sphere 2 (link1_c0) overlaps sphere 30 (link6_c0) by 0.004".
  std::string Describe(const Contact& contact) const;

 private:
  struct Probe;
  /// The probes of the calls on one thread, reused so that a call allocates nothing once they have grown.
  template <class P>
  struct ProbePool {
    std::vector<std::unique_ptr<P>> probes;
    size_t used = 0;
    P& Next() {
      if (used == probes.size()) probes.push_back(std::make_unique<P>());
      return *probes[used++];
    }
  };
  /// The motion between two placed configurations, its midpoints drawn from `pool`.
  MotionVerdict Between(Probe& first, Probe& last, ProbePool<Probe>& pool) const;
  void Fill(Probe& probe, const double* q) const;
  Contact Scan(Probe& probe, bool first_only, double* clearance) const;
  double LinkClearance(Probe& probe, int l, int k, double need) const;
  const double* Spheres(Probe& probe, int c) const;
  double ClusterClearance(const Probe& probe, int c, int k) const;
  const double* SphereClearances(Probe& probe, int c, int k) const;
  double PairGap(Probe& probe, int pair) const;
  double ClusterPairGap(Probe& probe, int pair, int ca, int cb) const;

  std::shared_ptr<const BodyModel> body_;
  std::shared_ptr<const World> world_;
  CheckSettings settings_;
  std::vector<int> pair_clusters_;  // (P + 1) where each self pair's cluster pairs start in Probe::cluster_gap
};

}  // namespace flowplan::collision
