#include "collision/checker.h"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace flowplan::collision {
namespace {

/// Asks LinkClearance for the exact clearance whatever the bound.
constexpr double kExact = std::numeric_limits<double>::infinity();

double Gap(const double* a, const double* b, int W) {
  double squares = 0.0;
  for (int i = 0; i < W; ++i) squares += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(squares);
}

}  // namespace

/// One configuration's placed body and what has been measured of it, each measure taken when first needed.
struct Checker::Probe {
  std::vector<double> q;              // (J)
  std::vector<Frame> frames;          // (L)
  std::vector<double> axes, points;   // (J, 3) the planned joints' axes and points on them
  std::vector<double> centres;        // (S, W), a cluster's rows once `placed`
  std::vector<uint8_t> placed;        // (C) whether the cluster's sphere centres are in `centres`
  std::vector<double> bounds;         // (L, W) the links' bounding sphere centres
  std::vector<double> clusters;       // (C, W) the clusters' bounding sphere centres
  std::vector<double> link_obstacle;  // (L, K) lower bound on each link's clearance from each obstacle
  std::vector<uint8_t> link_exact;    // (L, K) whether link_obstacle is the exact bounding-sphere clearance
  std::vector<double> link_floor;     // (L) each link's clearance above the floor (+inf: none, or exempt)
  std::vector<int32_t> slot;          // (C, K) where a cluster's spheres' clearances from the obstacle start in
                                      // `sphere`, -1 until measured
  std::vector<double> sphere;         // the measured spheres' clearances, cluster by cluster
  std::vector<double> pair_gap;       // (P) the gap between each self pair's bounding spheres (NaN: not yet)
  std::vector<double> cluster_gap;    // the smallest gap between the spheres of each cluster pair of each self
                                      // pair (Checker::pair_clusters_ numbering), valid where cluster_gap_fill
                                      // is `fill`: a robot with many clusters has tens of thousands of them, too
                                      // many to reset for every configuration placed
  std::vector<uint32_t> cluster_gap_fill;
  uint32_t fill = 0;                  // counts this probe's Fill calls
};


Checker::Checker(std::shared_ptr<const BodyModel> body, std::shared_ptr<const World> world, CheckSettings settings)
    : body_(std::move(body)), world_(std::move(world)), settings_(settings) {
  if (body_->workspace_dim() != world_->workspace_dim()) {
    throw Error("collision check: a " + std::to_string(body_->workspace_dim()) + "-D robot in a " +
                std::to_string(world_->workspace_dim()) + "-D world");
  }
  if (!(settings_.margin >= 0.0)) throw Error("collision check: margin: expected a non-negative margin");
  if (!(settings_.resolution > 0.0)) throw Error("collision check: resolution: expected a positive resolution");
  const BodyModel& b = *body_;
  pair_clusters_.assign(1, 0);
  for (const auto& [la, lb] : b.self_pairs()) {
    const int clusters_a = b.first_cluster(la + 1) - b.first_cluster(la);
    const int clusters_b = b.first_cluster(lb + 1) - b.first_cluster(lb);
    pair_clusters_.push_back(pair_clusters_.back() + clusters_a * clusters_b);
  }
}

void Checker::Fill(Probe& p, const double* q) const {
  const BodyModel& b = *body_;
  const World& w = *world_;
  const int J = b.num_joints(), L = b.num_links(), S = b.num_spheres(), W = b.workspace_dim(), K = w.size();
  p.q.assign(q, q + J);
  p.frames.resize(static_cast<size_t>(L));
  p.centres.resize(static_cast<size_t>(S * W));
  p.bounds.resize(static_cast<size_t>(L * W));
  p.clusters.resize(static_cast<size_t>(b.num_clusters() * W));
  b.PlaceFrames(q, p.frames.data());
  p.axes.resize(static_cast<size_t>(3 * J));
  p.points.resize(static_cast<size_t>(3 * J));
  b.JointAxes(p.frames.data(), p.axes.data(), p.points.data());
  b.PlaceBounds(q, p.frames.data(), p.bounds.data(), p.clusters.data());
  p.placed.assign(static_cast<size_t>(b.num_clusters()), 0);
  p.link_obstacle.resize(static_cast<size_t>(L * K));
  p.link_exact.assign(static_cast<size_t>(L * K), 0);
  p.link_floor.resize(static_cast<size_t>(L));
  for (int l = 0; l < L; ++l) {
    const double R = b.bound_radius(l);
    const double* c = &p.bounds[static_cast<size_t>(l * W)];
    // data() + offset, not &v[offset]: with no obstacles (K = 0) the vector is empty and has no element to refer to.
    w.LowerBounds(c, R, p.link_obstacle.data() + static_cast<size_t>(l * K));
    p.link_floor[static_cast<size_t>(l)] =
        b.floor_checked(l) && w.floor().present ? w.FloorDistance(c) - R : std::numeric_limits<double>::infinity();
  }
  p.slot.assign(static_cast<size_t>(b.num_clusters() * K), -1);
  p.sphere.clear();
  p.pair_gap.assign(b.self_pairs().size(), std::numeric_limits<double>::quiet_NaN());
  const size_t cluster_pairs = static_cast<size_t>(pair_clusters_.back());
  if (++p.fill == 0 || p.cluster_gap.size() != cluster_pairs) {  // first use, or the count wrapped around
    p.cluster_gap.assign(cluster_pairs, 0.0);
    p.cluster_gap_fill.assign(cluster_pairs, 0);
    p.fill = 1;
  }
}

/// Link l's clearance from obstacle k by its bounding sphere: the box bound, made exact when it is below `need`.
double Checker::LinkClearance(Probe& p, int l, int k, double need) const {
  const size_t at = static_cast<size_t>(l * world_->size() + k);
  double& d = p.link_obstacle[at];
  if (d < need && !p.link_exact[at]) {
    d = world_->Distance(k, &p.bounds[static_cast<size_t>(l * body_->workspace_dim())]) - body_->bound_radius(l);
    p.link_exact[at] = 1;
  }
  return d;
}

/// The centres of cluster c's spheres (their rows of p.centres), placed when first asked for.
const double* Checker::Spheres(Probe& p, int c) const {
  if (!p.placed[static_cast<size_t>(c)]) {
    body_->PlaceSpheres(p.q.data(), p.frames.data(), c, p.centres.data());
    p.placed[static_cast<size_t>(c)] = 1;
  }
  return p.centres.data();
}

/// Cluster c's clearance from obstacle k by its bounding sphere.
double Checker::ClusterClearance(const Probe& p, int c, int k) const {
  return world_->Distance(k, &p.clusters[static_cast<size_t>(c * body_->workspace_dim())]) - body_->cluster_radius(c);
}

/// The clearances of cluster c's spheres from obstacle k (first_in_cluster(c) .. first_in_cluster(c + 1) - 1).
const double* Checker::SphereClearances(Probe& p, int c, int k) const {
  const size_t at = static_cast<size_t>(c * world_->size() + k);
  if (p.slot[at] < 0) {
    p.slot[at] = static_cast<int32_t>(p.sphere.size());
    const int W = body_->workspace_dim();
    const double* centres = Spheres(p, c);
    for (int s = body_->first_in_cluster(c); s < body_->first_in_cluster(c + 1); ++s) {
      p.sphere.push_back(world_->Distance(k, &centres[static_cast<size_t>(s * W)]) - body_->sphere_radius(s));
    }
  }
  return &p.sphere[static_cast<size_t>(p.slot[at])];
}

double Checker::PairGap(Probe& p, int pair) const {
  double& g = p.pair_gap[static_cast<size_t>(pair)];
  if (std::isnan(g)) {
    const auto [la, lb] = body_->self_pairs()[static_cast<size_t>(pair)];
    const int W = body_->workspace_dim();
    g = Gap(&p.bounds[static_cast<size_t>(la * W)], &p.bounds[static_cast<size_t>(lb * W)], W) -
        body_->bound_radius(la) - body_->bound_radius(lb);
  }
  return g;
}

/// The smallest gap between a sphere of cluster ca (of self pair `pair`'s first link) and one of cluster cb (of
/// its second), exact.
double Checker::ClusterPairGap(Probe& p, int pair, int ca, int cb) const {
  const BodyModel& b = *body_;
  const auto [la, lb] = b.self_pairs()[static_cast<size_t>(pair)];
  const int clusters_b = b.first_cluster(lb + 1) - b.first_cluster(lb);
  const size_t at = static_cast<size_t>(pair_clusters_[static_cast<size_t>(pair)] +
                                        (ca - b.first_cluster(la)) * clusters_b + cb - b.first_cluster(lb));
  double& g = p.cluster_gap[at];
  if (p.cluster_gap_fill[at] != p.fill) {
    p.cluster_gap_fill[at] = p.fill;
    const int W = b.workspace_dim();
    Spheres(p, ca);
    Spheres(p, cb);
    double smallest = std::numeric_limits<double>::infinity();
    for (int sa = b.first_in_cluster(ca); sa < b.first_in_cluster(ca + 1); ++sa) {
      for (int sb = b.first_in_cluster(cb); sb < b.first_in_cluster(cb + 1); ++sb) {
        const double gap = Gap(&p.centres[static_cast<size_t>(sa * W)], &p.centres[static_cast<size_t>(sb * W)], W) -
                           b.sphere_radius(sa) - b.sphere_radius(sb);
        if (std::isnan(gap) || gap < smallest) smallest = gap;  // NaN stays: no screen passes it
      }
    }
    g = smallest;
  }
  return g;
}

Contact Checker::Scan(Probe& p, bool first_only, double* clearance) const {
  const BodyModel& b = *body_;
  const World& w = *world_;
  const int L = b.num_links(), K = w.size(), W = b.workspace_dim();
  const double margin = settings_.margin;
  Contact first;
  auto note = [&](Contact::Kind kind, int sphere, int other, double distance) {
    if (!first.found()) first = {kind, sphere, other, distance};
  };
  double best = std::numeric_limits<double>::infinity();
  for (int l = 0; l < L; ++l) {
    if (b.bound_radius(l) < 0) continue;
    const int s0 = b.first_sphere(l), s1 = b.first_sphere(l + 1);
    for (int k = 0; k < K; ++k) {
      // Screened by the link's bounding sphere, then each cluster's: clear by the margin, and (measuring the
      // clearance) no nearer than the nearest sphere found so far.
      double need = clearance == nullptr ? margin : std::max(margin, best);
      if (LinkClearance(p, l, k, need) >= need) continue;
      for (int c = b.first_cluster(l); c < b.first_cluster(l + 1); ++c) {
        need = clearance == nullptr ? margin : std::max(margin, best);
        if (ClusterClearance(p, c, k) >= need) continue;
        const int c0 = b.first_in_cluster(c), c1 = b.first_in_cluster(c + 1);
        const double* d = SphereClearances(p, c, k);
        for (int s = c0; s < c1; ++s) {
          best = std::min(best, d[s - c0]);
          if (!(d[s - c0] >= margin)) {
            note(Contact::Kind::kObstacle, s, k, d[s - c0]);
            if (first_only) return first;
          }
        }
      }
    }
    if (p.link_floor[static_cast<size_t>(l)] < margin) {
      for (int c = b.first_cluster(l); c < b.first_cluster(l + 1); ++c) Spheres(p, c);
      for (int s = s0; s < s1; ++s) {
        const double d = w.FloorDistance(&p.centres[static_cast<size_t>(s * W)]) - b.sphere_radius(s);
        if (!(d >= margin)) {
          note(Contact::Kind::kFloor, s, -1, d);
          if (first_only) return first;
        }
      }
    }
  }
  for (size_t pair = 0; pair < b.self_pairs().size(); ++pair) {
    if (PairGap(p, static_cast<int>(pair)) >= 0.0) continue;
    const auto [la, lb] = b.self_pairs()[pair];
    for (int ca = b.first_cluster(la); ca < b.first_cluster(la + 1); ++ca) {
      for (int cb = b.first_cluster(lb); cb < b.first_cluster(lb + 1); ++cb) {
        if (Gap(&p.clusters[static_cast<size_t>(ca * W)], &p.clusters[static_cast<size_t>(cb * W)], W) -
                b.cluster_radius(ca) - b.cluster_radius(cb) >= 0.0) {
          continue;
        }
        if (ClusterPairGap(p, static_cast<int>(pair), ca, cb) >= 0.0) continue;
        Spheres(p, ca);
        Spheres(p, cb);
        for (int sa = b.first_in_cluster(ca); sa < b.first_in_cluster(ca + 1); ++sa) {
          for (int sb = b.first_in_cluster(cb); sb < b.first_in_cluster(cb + 1); ++sb) {
            const double g =
                Gap(&p.centres[static_cast<size_t>(sa * W)], &p.centres[static_cast<size_t>(sb * W)], W) -
                b.sphere_radius(sa) - b.sphere_radius(sb);
            if (!(g >= 0.0)) {
              note(Contact::Kind::kSelf, sa, sb, g);
              if (first_only) return first;
            }
          }
        }
      }
    }
  }
  if (clearance != nullptr) *clearance = best;
  return first;
}

namespace {

bool Finite(const double* q, int J) {
  for (int j = 0; j < J; ++j) {
    if (!std::isfinite(q[j])) return false;
  }
  return true;
}

}  // namespace

bool Checker::Valid(const double* q) const { return !FirstContact(q).found(); }

Contact Checker::FirstContact(const double* q) const {
  if (!Finite(q, body_->num_joints())) return {Contact::Kind::kObstacle, 0, -1, std::numeric_limits<double>::quiet_NaN()};
  thread_local ProbePool<Probe> pool;
  pool.used = 0;
  Probe& p = pool.Next();
  Fill(p, q);
  return Scan(p, true, nullptr);
}

double Checker::Clearance(const double* q) const {
  if (!Finite(q, body_->num_joints())) return std::numeric_limits<double>::quiet_NaN();
  thread_local ProbePool<Probe> pool;
  pool.used = 0;
  Probe& p = pool.Next();
  Fill(p, q);
  double clearance = std::numeric_limits<double>::infinity();
  Scan(p, false, &clearance);
  return clearance;
}

MotionVerdict Checker::CheckMotion(const double* qa, const double* qb) const {
  const int J = body_->num_joints();
  if (!Finite(qa, J) || !Finite(qb, J)) {
    MotionVerdict verdict;
    verdict.valid = false;
    verdict.contact = {Contact::Kind::kObstacle, 0, -1, std::numeric_limits<double>::quiet_NaN()};
    return verdict;
  }
  thread_local ProbePool<Probe> pool;
  pool.used = 0;
  Probe& first = pool.Next();
  Probe& last = pool.Next();
  Fill(first, qa);
  Fill(last, qb);
  return Between(first, last, pool);
}

PathVerdict Checker::CheckPath(const double* q, int n) const {
  if (n < 0) throw InternalError("collision check: a path of " + std::to_string(n) + " states");
  const int J = body_->num_joints();
  PathVerdict verdict;
  // Each state placed once, its measures kept for the motions on either side of it.
  thread_local ProbePool<Probe> states;
  thread_local ProbePool<Probe> pool;
  states.used = 0;
  for (int t = 0; t < n; ++t) {
    const double* state = q + static_cast<size_t>(t) * static_cast<size_t>(J);
    if (!Finite(state, J)) {
      verdict.state = t;
      verdict.state_contact = {Contact::Kind::kObstacle, 0, -1, std::numeric_limits<double>::quiet_NaN()};
      return verdict;
    }
    Probe& p = states.Next();
    Fill(p, state);
    const Contact contact = Scan(p, true, nullptr);
    if (contact.found()) {
      verdict.state = t;
      verdict.state_contact = contact;
      return verdict;
    }
  }
  for (int t = 0; t + 1 < n; ++t) {
    pool.used = 0;
    const MotionVerdict motion = Between(*states.probes[static_cast<size_t>(t)],
                                         *states.probes[static_cast<size_t>(t + 1)], pool);
    verdict.checks += motion.checks;
    if (!motion.valid) {
      verdict.motion = t;
      verdict.motion_verdict = motion;
      return verdict;
    }
  }
  return verdict;
}

MotionVerdict Checker::Between(Probe& first, Probe& last, ProbePool<Probe>& pool) const {
  const BodyModel& b = *body_;
  const World& w = *world_;
  const int J = b.num_joints(), L = b.num_links(), K = w.size(), W = b.workspace_dim();
  const int P = static_cast<int>(b.self_pairs().size());
  const double margin = settings_.margin, resolution = settings_.resolution;
  MotionVerdict verdict;
  struct Piece {
    Probe* a;
    Probe* b;
    double from, to;  // fractions of the whole segment
  };
  // Pieces are looked at coarse to fine (breadth first): a motion that is not valid is usually found so after a
  // few configurations, before its valid stretches are certified.
  thread_local std::vector<Piece> queue;
  thread_local std::vector<double> dq, qm, link_static, link_travel, cluster_travel;
  queue.assign(1, {&first, &last, 0.0, 1.0});
  size_t next_piece = 0;
  dq.resize(static_cast<size_t>(J));
  qm.resize(static_cast<size_t>(J));
  link_static.resize(static_cast<size_t>(L));
  link_travel.resize(static_cast<size_t>(L));
  cluster_travel.resize(static_cast<size_t>(b.num_clusters()));
  // Along a piece, every point within link l's bounding sphere moves at most link_travel[l] (BodyModel::Travel,
  // from either end); the distance between a point of link a and one of link b changes by at most what the
  // joints that move one link and not the other move them.
  auto travel = [&](const Probe& A, const Probe& B, int l, uint64_t joints) {
    const double* d = dq.data();
    const size_t at = static_cast<size_t>(l * W);
    return std::min(b.Travel(l, joints, d, A.axes.data(), A.points.data(), &A.bounds[at]),
                    b.Travel(l, joints, d, B.axes.data(), B.points.data(), &B.bounds[at]));
  };
  // The same bound for a cluster of link l: its bounding sphere's travel, no more than its link's `bound`.
  auto travel_of_cluster = [&](const Probe& A, const Probe& B, int l, int c, uint64_t joints, double bound) {
    const double* d = dq.data();
    const size_t at = static_cast<size_t>(c * W);
    const double r = b.cluster_radius(c);
    return std::min({bound, b.Travel(l, joints, d, A.axes.data(), A.points.data(), &A.clusters[at], r),
                     b.Travel(l, joints, d, B.axes.data(), B.points.data(), &B.clusters[at], r)});
  };
  while (next_piece < queue.size()) {
    const Piece piece = queue[next_piece++];
    Probe& A = *piece.a;
    Probe& B = *piece.b;
    for (int j = 0; j < J; ++j) dq[static_cast<size_t>(j)] = std::abs(B.q[static_cast<size_t>(j)] - A.q[static_cast<size_t>(j)]);
    // Each link's static travel bound first (cheap, never below the tight one); the tight bound only for the
    // links whose distances the static one does not certify (NaN until then).
    for (int l = 0; l < L; ++l) {
      link_static[static_cast<size_t>(l)] = b.bound_radius(l) < 0 ? 0.0 : b.StaticTravel(l, b.ancestor_joints(l), dq.data());
      link_travel[static_cast<size_t>(l)] = std::numeric_limits<double>::quiet_NaN();
    }
    std::fill(cluster_travel.begin(), cluster_travel.end(), std::numeric_limits<double>::quiet_NaN());
    auto tight = [&](int l) {
      double& t = link_travel[static_cast<size_t>(l)];
      if (std::isnan(t)) t = b.bound_radius(l) < 0 ? 0.0 : travel(A, B, l, b.ancestor_joints(l));
      return t;
    };
    // Whether link l's clearances from obstacle k at the two ends (box bounds first, then the bounding spheres')
    // add up to `need`.
    auto link_clear = [&](int l, int k, double need) {
      double la = LinkClearance(A, l, k, need), lb = LinkClearance(B, l, k, need - la);
      if (la + lb < need) {  // the box bounds may be loose: the bounding spheres' own clearances
        la = LinkClearance(A, l, k, kExact);
        lb = LinkClearance(B, l, k, kExact);
      }
      return la + lb >= need;
    };
    // Whether the piece must be halved: some distance is not certified, and its points move at least
    // `resolution` (pieces whose uncertain points all move less are accepted).
    bool halve = false;
    for (int l = 0; l < L && !halve; ++l) {
      if (b.bound_radius(l) < 0) continue;
      const double t_static = link_static[static_cast<size_t>(l)];
      const int s0 = b.first_sphere(l), s1 = b.first_sphere(l + 1);
      for (int k = 0; k < K && !halve; ++k) {
        if (link_clear(l, k, 2.0 * margin + t_static)) continue;
        const double t = tight(l);
        const double need = 2.0 * margin + t;  // what the two ends' clearances must add up to
        if (t < t_static && link_clear(l, k, need)) continue;
        for (int c = b.first_cluster(l); c < b.first_cluster(l + 1) && !halve; ++c) {
          if (ClusterClearance(A, c, k) + ClusterClearance(B, c, k) >= need) continue;
          // The cluster's own travel: a cluster near the moving joints' axes moves less than its link's far end.
          double& tc = cluster_travel[static_cast<size_t>(c)];
          if (std::isnan(tc)) tc = travel_of_cluster(A, B, l, c, b.ancestor_joints(l), t);
          const double need_c = 2.0 * margin + tc;
          if (ClusterClearance(A, c, k) + ClusterClearance(B, c, k) >= need_c) continue;
          const int c0 = b.first_in_cluster(c), c1 = b.first_in_cluster(c + 1);
          const double* da = SphereClearances(A, c, k);
          const double* db = SphereClearances(B, c, k);
          for (int s = c0; s < c1 && !halve; ++s) {
            if (da[s - c0] + db[s - c0] >= need_c) continue;
            halve = tc >= resolution;
          }
        }
      }
      const size_t l_at = static_cast<size_t>(l);
      if (!halve && A.link_floor[l_at] + B.link_floor[l_at] < 2.0 * margin + t_static &&
          A.link_floor[l_at] + B.link_floor[l_at] < 2.0 * margin + tight(l)) {
        const double t = tight(l);
        const double need = 2.0 * margin + t;
        for (int c = b.first_cluster(l); c < b.first_cluster(l + 1); ++c) {
          Spheres(A, c);
          Spheres(B, c);
        }
        for (int s = s0; s < s1 && !halve; ++s) {
          const double da = w.FloorDistance(&A.centres[static_cast<size_t>(s * W)]) - b.sphere_radius(s);
          const double db = w.FloorDistance(&B.centres[static_cast<size_t>(s * W)]) - b.sphere_radius(s);
          if (da + db >= need) continue;
          halve = t >= resolution;
        }
      }
    }
    for (int pair = 0; pair < P && !halve; ++pair) {
      const auto [la, lb] = b.self_pairs()[static_cast<size_t>(pair)];
      const uint64_t only_a = b.ancestor_joints(la) & ~b.ancestor_joints(lb);
      const uint64_t only_b = b.ancestor_joints(lb) & ~b.ancestor_joints(la);
      const double gaps = PairGap(A, pair) + PairGap(B, pair);
      if (gaps >= link_static[static_cast<size_t>(la)] + link_static[static_cast<size_t>(lb)]) continue;
      const double ta = travel(A, B, la, only_a), tb = travel(A, B, lb, only_b), t = ta + tb;
      if (gaps >= t) continue;
      for (int ca = b.first_cluster(la); ca < b.first_cluster(la + 1) && !halve; ++ca) {
        double tca = -1.0;  // cluster ca's own travel, when first needed
        for (int cb = b.first_cluster(lb); cb < b.first_cluster(lb + 1) && !halve; ++cb) {
          auto cluster_gap = [&](const Probe& Q) {
            return Gap(&Q.clusters[static_cast<size_t>(ca * W)], &Q.clusters[static_cast<size_t>(cb * W)], W) -
                   b.cluster_radius(ca) - b.cluster_radius(cb);
          };
          const double gaps_c = cluster_gap(A) + cluster_gap(B);
          if (gaps_c >= t) continue;
          // The two clusters' own travels: links that stay close (a wrist and its hand) stay so only near
          // the joint between them, where their parts move least.
          if (tca < 0.0) tca = travel_of_cluster(A, B, la, ca, only_a, ta);
          const double tc = tca + travel_of_cluster(A, B, lb, cb, only_b, tb);
          if (gaps_c >= tc) continue;
          // Each end's smallest sphere gap (measured once per configuration), then sphere pair by sphere pair.
          if (ClusterPairGap(A, pair, ca, cb) + ClusterPairGap(B, pair, ca, cb) >= tc) continue;
          Spheres(A, ca);
          Spheres(A, cb);
          Spheres(B, ca);
          Spheres(B, cb);
          for (int sa = b.first_in_cluster(ca); sa < b.first_in_cluster(ca + 1) && !halve; ++sa) {
            for (int sb = b.first_in_cluster(cb); sb < b.first_in_cluster(cb + 1) && !halve; ++sb) {
              auto gap = [&](const Probe& Q) {
                return Gap(&Q.centres[static_cast<size_t>(sa * W)], &Q.centres[static_cast<size_t>(sb * W)], W) -
                       b.sphere_radius(sa) - b.sphere_radius(sb);
              };
              if (gap(A) + gap(B) >= tc) continue;
              halve = tc >= resolution;
            }
          }
        }
      }
    }
    if (!halve) continue;
    Probe& M = pool.Next();
    for (int j = 0; j < J; ++j) qm[static_cast<size_t>(j)] = 0.5 * (A.q[static_cast<size_t>(j)] + B.q[static_cast<size_t>(j)]);
    Fill(M, qm.data());
    ++verdict.checks;
    const double middle = 0.5 * (piece.from + piece.to);
    const Contact contact = Scan(M, true, nullptr);
    if (contact.found()) {
      verdict.valid = false;
      verdict.fraction = middle;
      verdict.contact = contact;
      return verdict;
    }
    queue.push_back({piece.a, &M, piece.from, middle});
    queue.push_back({&M, piece.b, middle, piece.to});
  }
  return verdict;
}

std::string Checker::Describe(const Contact& contact) const {
  const BodyModel& b = *body_;
  auto num = [](double v) { return fmt::format("{:.4g}", v); };
  switch (contact.kind) {
    case Contact::Kind::kNone: return "";
    case Contact::Kind::kObstacle:
      if (contact.other < 0) return "a configuration holds NaN or an infinity";
      return b.sphere_name(contact.sphere) + " is " + num(contact.distance) + " from obstacle " +
             std::to_string(contact.other) + " (" + world_->obstacle(contact.other).name + ")";
    case Contact::Kind::kFloor:
      return b.sphere_name(contact.sphere) + " is " + num(contact.distance) + " from the floor";
    case Contact::Kind::kSelf:
      return b.sphere_name(contact.sphere) + " on " + b.link_name(b.sphere_link(contact.sphere)) + " overlaps " +
             b.sphere_name(contact.other) + " on " + b.link_name(b.sphere_link(contact.other)) + " by " +
             num(-contact.distance);
  }
  return "";
}

}  // namespace flowplan::collision
