// Cover: how the spheres are chosen.
//
// The requirement is that the union of spheres contains the whole surface, not
// only sample points (a denser check must find nothing uncovered). A ball is
// convex, so it contains a triangle exactly when it contains its three
// corners. The surface is therefore cut into small triangles ("pieces", edges
// no longer than min(spacing, overshoot / 2), by longest-edge bisection) and
// every piece must lie inside one chosen sphere: then every point of the
// surface is covered, exactly — an improvement on covering sample points,
// which leaves gaps between them.
//
// Candidate spheres, each reaching at most `overshoot` outside a closed mesh:
//  - interior grid points c (|winding number| > 0.9), radius dist(c, surface) +
//    overshoot: a point of the ball outside the mesh is at most
//    r - dist(c) = overshoot from the surface, since the segment from c to it
//    crosses the surface no nearer to c than dist(c). The grid has ~12 steps
//    along the longest side and is refined while few of its points fall
//    inside (thin shapes);
//  - medial points, one per surface seed point p: instead of the midpoint of
//    p and the opposite wall along the inward normal, the shrinking-ball
//    iteration (Ma et al. 2012) finds the largest ball touching the surface at
//    p and nowhere closer, i.e. a point of the medial axis. These centres are
//    as deep as possible for the surface near p, so their spheres cover the
//    most surface for the allowed overshoot, also in thin parts and corners
//    the grid misses;
//  - surface points (the seed points and the mesh's vertices, at most 3000 of
//    them), radius overshoot: the only spheres an open or paper-thin mesh allows;
//  - for each piece no candidate contains: a sphere of radius overshoot at its
//    centroid (which holds the piece, as pieces are at most overshoot / 2 long).
// Sites closer than spacing / 4 to an earlier one of the same kind are dropped.
//
// Selection is the lazy greedy set cover (each step takes the candidate
// containing the most still-uncovered pieces; ties by candidate order). If
// max_spheres is reached first, the cover is computed again for larger
// overshoots — doubled, then bisected on a log scale — and the least one
// (within about 9 %) whose cover fits is kept. This replaces raising the radii
// of a few chosen spheres to reach the leftovers (still the last resort):
// every sphere then stays within one, larger, overshoot. Measured on a 1164-triangle link capped at 64 spheres with overshoot
// 0.003 m: reach 0.012 m and 0.47 of its volume outside, against 0.018 m and
// 0.49 by raising radii; on a box capped at 6: 0.022 m / 1.67 against
// 0.025 m / 1.52.
//
// Then spheres all of whose pieces another sphere also contains are dropped
// (latest first), every piece is assigned to the sphere it sits deepest in
// (relative to the radius) and each radius shrinks to its assigned pieces'
// farthest corner (three rounds) — tighter than distance + overshoot wherever
// the overshoot was not needed. Finally every point of
// SurfaceSamples(mesh, spacing, seed) is checked. Radii carry a relative pad
// of 1e-12 against rounding.

#include "spheres/cover.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <queue>
#include <set>
#include <string>

#include "core/error.h"
#include "core/random.h"
#include "spheres/internal_geometry.h"
#include "spheres/mesh_index.h"

namespace flowplan::spheres {
namespace {

using internal::NumberText;
using internal::Vec3;

constexpr double kPad = 1e-12;              // relative radius padding against rounding
constexpr int kGridSteps = 12;              // interior grid steps along the longest side
constexpr int kMinInteriorGridPoints = 300;  // refine the grid (thin shapes) below this
constexpr int64_t kMaxGridPoints = 200000;
constexpr int kMedialSeeds = 3000;          // surface points the medial candidates start from
constexpr size_t kMaxPieces = 4000000;
constexpr double kInteriorWinding = 0.9;     // |winding number| of an interior candidate centre

struct Piece {
  Vec3 a, b, c;
  Vec3 centroid;
};

struct Candidate {
  Vec3 centre;
  double radius;
};

Piece MakePiece(const Vec3& a, const Vec3& b, const Vec3& c) { return {a, b, c, (a + b + c) * (1.0 / 3.0)}; }

// The largest distance from `centre` to a corner of the piece.
double FarthestCorner(const Piece& piece, const Vec3& centre) {
  return std::sqrt(std::max({SquaredDistance(piece.a, centre), SquaredDistance(piece.b, centre),
                             SquaredDistance(piece.c, centre)}));
}

bool Contains(const Vec3& centre, double radius, const Piece& piece) {
  const double r2 = radius * radius;
  return SquaredDistance(piece.a, centre) <= r2 && SquaredDistance(piece.b, centre) <= r2 &&
         SquaredDistance(piece.c, centre) <= r2;
}

// Longest-edge bisection of (a, b, c) until no edge is longer than `limit`;
// stops adding once `out` holds kMaxPieces.
void Split(const Vec3& a, const Vec3& b, const Vec3& c, double limit2, std::vector<Piece>& out) {
  if (out.size() >= kMaxPieces) return;
  const double ab = SquaredDistance(a, b), bc = SquaredDistance(b, c), ca = SquaredDistance(c, a);
  if (std::max({ab, bc, ca}) <= limit2) {
    out.push_back(MakePiece(a, b, c));
    return;
  }
  if (ab >= bc && ab >= ca) {
    const Vec3 m = (a + b) * 0.5;
    Split(a, m, c, limit2, out);
    Split(m, b, c, limit2, out);
  } else if (bc >= ca) {
    const Vec3 m = (b + c) * 0.5;
    Split(a, b, m, limit2, out);
    Split(a, m, c, limit2, out);
  } else {
    const Vec3 m = (c + a) * 0.5;
    Split(a, b, m, limit2, out);
    Split(m, b, c, limit2, out);
  }
}

// The pieces not yet covered, bucketed by centroid in a uniform grid, for
// "which live pieces does this ball contain" queries.
class PieceGrid {
 public:
  PieceGrid(const std::vector<Piece>& pieces, const Vec3& lo, const Vec3& hi, double cell) : pieces_(pieces) {
    cell_ = cell;
    lo_ = lo;
    for (int k = 0; k < 3; ++k) {
      dims_[k] = std::max(1, static_cast<int>(std::ceil((hi[k] - lo[k]) / cell)) + 1);
    }
    cells_.resize(static_cast<size_t>(dims_[0]) * dims_[1] * dims_[2]);
    cell_of_.resize(pieces.size());
    slot_of_.resize(pieces.size());
    for (size_t e = 0; e < pieces.size(); ++e) {
      int ijk[3];
      for (int k = 0; k < 3; ++k) ijk[k] = Clamp((pieces[e].centroid[k] - lo_[k]) / cell_, k);
      const size_t cell_index = Flat(ijk[0], ijk[1], ijk[2]);
      cell_of_[e] = static_cast<int>(cell_index);
      slot_of_[e] = static_cast<int>(cells_[cell_index].size());
      cells_[cell_index].push_back(static_cast<int>(e));
    }
    // Each cell's bounding box of its pieces' corners (kept as pieces leave: a superset is still a bound).
    box_lo_.assign(cells_.size(), Vec3(INFINITY, INFINITY, INFINITY));
    box_hi_.assign(cells_.size(), Vec3(-INFINITY, -INFINITY, -INFINITY));
    for (size_t e = 0; e < pieces.size(); ++e) {
      const size_t c = static_cast<size_t>(cell_of_[e]);
      for (const Vec3* corner : {&pieces[e].a, &pieces[e].b, &pieces[e].c}) {
        box_lo_[c] = Min(box_lo_[c], *corner);
        box_hi_[c] = Max(box_hi_[c], *corner);
      }
    }
    live_ = static_cast<int64_t>(pieces.size());
    // The pieces lie on a surface, so most cells are empty: each column (i, j)
    // lists its non-empty cells' k, and queries walk only those.
    column_start_.assign(static_cast<size_t>(dims_[0]) * dims_[1] + 1, 0);
    for (int i = 0; i < dims_[0]; ++i) {
      for (int j = 0; j < dims_[1]; ++j) {
        for (int k = 0; k < dims_[2]; ++k) {
          if (!cells_[Flat(i, j, k)].empty()) column_k_.push_back(k);
        }
        column_start_[static_cast<size_t>(i) * dims_[1] + j + 1] = static_cast<int>(column_k_.size());
      }
    }
  }

  int64_t live() const { return live_; }

  // Visits the live pieces inside the ball: on_cell(cell) for a cell whose
  // pieces are all inside (a cheap bound shows it), on_piece(piece index)
  // for each other piece inside.
  template <class OnCell, class OnPiece>
  void Visit(const Vec3& centre, double radius, OnCell on_cell, OnPiece on_piece) const {
    int lo[3], hi[3];
    const double reach = radius * (1.0 + 1e-9) + 1e-9 * cell_;
    for (int k = 0; k < 3; ++k) {
      lo[k] = Clamp((centre[k] - reach - lo_[k]) / cell_, k);
      hi[k] = Clamp((centre[k] + reach - lo_[k]) / cell_, k);
    }
    const double r2 = radius * radius;
    const double loose_r2 = r2 * (1.0 + 1e-9);  // the centroid test only filters; Contains decides
    const double sure_r2 = r2 * (1.0 - 1e-12);  // margin for rounding: what is sure here, Contains confirms
    for (int i = lo[0]; i <= hi[0]; ++i) {
      for (int j = lo[1]; j <= hi[1]; ++j) {
        const size_t column = static_cast<size_t>(i) * dims_[1] + j;
        const auto first = column_k_.begin() + column_start_[column];
        const auto last = column_k_.begin() + column_start_[column + 1];
        for (auto it = std::lower_bound(first, last, lo[2]); it != last && *it <= hi[2]; ++it) {
          const int k = *it;
          const size_t flat = Flat(i, j, k);
          const auto& cell = cells_[flat];
          if (cell.empty()) continue;
          // A piece inside has all its corners inside, so some point of the
          // corners' box must be; if the box's farthest corner is inside, all are.
          const Vec3& box_lo = box_lo_[flat];
          const Vec3& box_hi = box_hi_[flat];
          if (SquaredDistanceToBox(centre, box_lo, box_hi) > loose_r2) continue;
          double far2 = 0.0;
          for (int a = 0; a < 3; ++a) {
            const double d = std::max(std::abs(centre[a] - box_lo[a]), std::abs(centre[a] - box_hi[a]));
            far2 += d * d;
          }
          if (far2 <= sure_r2) {
            on_cell(flat);
            continue;
          }
          for (int e : cell) {
            const Piece& piece = pieces_[e];
            // The centroid is in the ball when the piece is (convexity).
            if (SquaredDistance(piece.centroid, centre) <= loose_r2 && Contains(centre, radius, piece)) on_piece(e);
          }
        }
      }
    }
  }

  // Calls f(piece index) for every live piece inside the ball.
  template <class F>
  void ForEachContained(const Vec3& centre, double radius, F f) const {
    auto whole_cell = [&](size_t flat) {
      for (int e : cells_[flat]) f(e);
    };
    Visit(centre, radius, whole_cell, f);
  }

  int64_t CountContained(const Vec3& centre, double radius) const {
    int64_t count = 0;
    auto whole_cell = [&](size_t flat) { count += static_cast<int64_t>(cells_[flat].size()); };
    Visit(centre, radius, whole_cell, [&](int) { ++count; });
    return count;
  }

  size_t num_cells() const { return cells_.size(); }
  size_t cell_size(size_t flat) const { return cells_[flat].size(); }
  size_t cell_of(int e) const { return static_cast<size_t>(cell_of_[e]); }

  void Remove(int e) {
    auto& cell = cells_[static_cast<size_t>(cell_of_[e])];
    const int slot = slot_of_[e];
    const int last = cell.back();
    cell[static_cast<size_t>(slot)] = last;
    slot_of_[last] = slot;
    cell.pop_back();
    --live_;
  }

  // The live pieces, in index order.
  std::vector<int> Live() const {
    std::vector<int> out;
    for (const auto& cell : cells_) out.insert(out.end(), cell.begin(), cell.end());
    std::sort(out.begin(), out.end());
    return out;
  }

 private:
  int Clamp(double x, int k) const {
    if (!(x > 0.0)) return 0;
    return std::min(dims_[k] - 1, static_cast<int>(x));
  }
  size_t Flat(int i, int j, int k) const {
    return (static_cast<size_t>(i) * dims_[1] + static_cast<size_t>(j)) * dims_[2] + static_cast<size_t>(k);
  }

  const std::vector<Piece>& pieces_;
  double cell_ = 1.0;
  std::vector<Vec3> box_lo_, box_hi_;  // per cell: bounding box of its pieces' corners
  Vec3 lo_;
  int dims_[3] = {1, 1, 1};
  std::vector<std::vector<int>> cells_;
  std::vector<int> cell_of_, slot_of_;
  std::vector<int> column_start_, column_k_;  // column (i, j): its non-empty cells' k, ascending
  int64_t live_ = 0;
};

void CheckSettings(const CoverSettings& s) {
  if (!(std::isfinite(s.overshoot) && s.overshoot > 0.0)) {
    throw Error("CoverSettings.overshoot: expected a positive finite length (m), got " + NumberText(s.overshoot));
  }
  if (!(std::isfinite(s.spacing) && s.spacing > 0.0)) {
    throw Error("CoverSettings.spacing: expected a positive finite length (m), got " + NumberText(s.spacing));
  }
  if (s.max_spheres < 1) {
    throw Error("CoverSettings.max_spheres: expected at least 1, got " + std::to_string(s.max_spheres));
  }
}

// The shrinking-ball iteration (Ma, Bae, Choi, Wu 2012) from surface point p
// with unit inward normal n: the ball tangent to the surface at p is shrunk
// to pass through the nearest surface point q until no surface point is
// closer to its centre than its radius. Returns false if it collapses.
bool MedialPoint(const MeshIndex& index, const Vec3& p, const Vec3& n, double start_radius, Vec3* centre,
                 double* distance) {
  double r = start_radius;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const Vec3 c = p + n * r;
    Vec3 q;
    const double d = index.DistanceTo(c, &q);
    if (d >= r * (1.0 - 1e-9)) break;
    // The ball touching p (tangent there) and q: |c - q| = r with c = p + n r.
    const double denominator = 2.0 * Dot(n, q - p);
    if (!(denominator > 0.0)) return false;
    const double next = SquaredNorm(q - p) / denominator;
    if (!(next < r)) break;
    r = next;
  }
  if (!(r > 1e-9 * start_radius)) return false;
  *centre = p + n * r;
  *distance = index.DistanceTo(*centre);
  return *distance > 0.0;
}

struct HeapEntry {
  int64_t gain;
  int candidate;
  // std::priority_queue pops the largest: the most gain, then the lowest index.
  bool operator<(const HeapEntry& o) const { return gain < o.gain || (gain == o.gain && candidate > o.candidate); }
};

double Padded(double r) { return r * (1.0 + kPad); }

// A candidate centre and its distance to the surface (0 for a centre on it):
// its sphere for an overshoot o has radius depth + o. Independent of o, so
// computed once per Cover call.
struct Site {
  Vec3 centre;
  double depth;
};

// The candidate centres of a mesh (see the comment at the top).
std::vector<Site> Sites(const Mesh& mesh, const MeshIndex& index, const CoverSettings& settings) {
  const Vec3 lo(index.lower()), hi(index.upper());
  const Vec3 extent = hi - lo;
  const double size = std::max({extent.x, extent.y, extent.z});
  const double orientation = internal::SignedVolume(mesh) < 0.0 ? -1.0 : 1.0;
  // A centre counts as interior only well inside: the overshoot bound needs every
  // way out of its ball to cross the surface, which a large hole (winding
  // numbers between 0.5 and 0.9 around it) does not ensure. Inside a closed
  // mesh the winding number is 1.
  auto inside = [&](const Vec3& p) { return std::abs(index.WindingNumberAt(p)) > kInteriorWinding; };
  std::vector<Site> sites;

  // Interior grid, offset by a seeded fraction of a step, refined for thin shapes.
  if (size > 0.0) {
    Rng rng(StreamSeed(settings.seed, 1));
    const Vec3 jitter(rng.Uniform(), rng.Uniform(), rng.Uniform());
    double step = size / kGridSteps;
    for (;;) {
      std::vector<Site> grid;
      int n[3];
      for (int k = 0; k < 3; ++k) n[k] = static_cast<int>(std::floor(extent[k] / step - jitter[k])) + 1;
      for (int i = 0; i < n[0]; ++i) {
        for (int j = 0; j < n[1]; ++j) {
          for (int k = 0; k < n[2]; ++k) {
            const Vec3 p = lo + Vec3((i + jitter.x) * step, (j + jitter.y) * step, (k + jitter.z) * step);
            if (!inside(p)) continue;
            const double d = index.DistanceTo(p);
            if (d > 0.0) grid.push_back({p, d});
          }
        }
      }
      const auto points = static_cast<int64_t>(n[0]) * n[1] * n[2];
      if (static_cast<int>(grid.size()) >= kMinInteriorGridPoints || step * 0.5 < 0.5 * settings.spacing ||
          8 * points > kMaxGridPoints) {
        sites.insert(sites.end(), grid.begin(), grid.end());
        break;
      }
      step *= 0.5;
    }
  }

  // Medial points from seeded surface points; the seeds and the vertices as surface centres.
  std::vector<Vec3> surface;
  const double area = MeshArea(mesh);
  const double seed_spacing = std::max(settings.spacing, std::sqrt(area / kMedialSeeds));
  std::vector<int> seed_triangle;
  const auto seeds = internal::RandomSurfacePoints(mesh, seed_spacing, StreamSeed(settings.seed, 0), &seed_triangle);
  for (size_t s = 0; s < seeds.size(); ++s) {
    const auto& t = mesh.triangles[static_cast<size_t>(seed_triangle[s])];
    const Vec3 a(mesh.vertices[t[0]]), b(mesh.vertices[t[1]]), c(mesh.vertices[t[2]]);
    const Vec3 normal = Cross(b - a, c - a);
    const double length = Norm(normal);
    const Vec3 p(seeds[s]);
    surface.push_back(p);
    if (!(length > 0.0)) continue;
    const Vec3 inward = normal * (-orientation / length);
    // The inward side first; the other if this triangle is flipped.
    for (const Vec3& n : {inward, -inward}) {
      Vec3 centre;
      double distance;
      if (MedialPoint(index, p, n, size, &centre, &distance) && inside(centre)) {
        sites.push_back({centre, distance});
        break;
      }
    }
  }
  std::vector<std::array<double, 3>> vertices;
  for (const auto& t : mesh.triangles) {
    for (int v : t) vertices.push_back(mesh.vertices[static_cast<size_t>(v)]);
  }
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  // A fine mesh's vertices are many and add little to the seeds; every k-th is enough.
  const size_t stride = (vertices.size() + kMedialSeeds - 1) / kMedialSeeds;
  for (size_t v = 0; v < vertices.size(); v += std::max<size_t>(stride, 1)) surface.emplace_back(vertices[v]);
  for (const Vec3& p : surface) sites.push_back({p, 0.0});

  // Sites closer than spacing / 4 to an earlier one of the same kind (inside or
  // on the surface) add nothing but time: a round part's medial seeds all fall
  // on its axis. The first of each is kept.
  const double quantum = 0.25 * settings.spacing;
  std::set<std::array<int64_t, 4>> seen;
  std::vector<Site> kept;
  for (const Site& site : sites) {
    const std::array<int64_t, 4> key = {std::llround((site.centre.x - lo.x) / quantum),
                                        std::llround((site.centre.y - lo.y) / quantum),
                                        std::llround((site.centre.z - lo.z) / quantum), site.depth > 0.0 ? 1 : 0};
    if (seen.insert(key).second) kept.push_back(site);
  }
  return kept;
}

// The greedy cover for one overshoot: the pieces it was computed on, the
// spheres chosen (at most max_spheres) and the pieces none of them holds.
struct Selection {
  std::vector<Piece> pieces;
  std::vector<Candidate> chosen;
  std::vector<int> leftover;
};

Selection Select(const Mesh& mesh, const MeshIndex& index, const std::vector<Site>& sites, double overshoot,
                 double spacing, int max_spheres) {
  Selection out;
  const Vec3 lo(index.lower()), hi(index.upper());
  const Vec3 extent = hi - lo;
  const double size = std::max({extent.x, extent.y, extent.z});

  // Pieces of the surface.
  std::vector<Piece>& pieces = out.pieces;
  const double piece_edge = std::min(spacing, 0.5 * overshoot);
  const double limit2 = piece_edge * piece_edge;
  for (const auto& t : mesh.triangles) {
    Split(Vec3(mesh.vertices[t[0]]), Vec3(mesh.vertices[t[1]]), Vec3(mesh.vertices[t[2]]), limit2, pieces);
  }
  if (pieces.size() >= kMaxPieces) {
    throw Error("Cover: CoverSettings.spacing " + NumberText(spacing) + " m with overshoot " + NumberText(overshoot) +
                " m cuts the surface (" + NumberText(MeshArea(mesh)) + " m^2) into more than 4e6 pieces of edges <= " +
                NumberText(piece_edge) + " m = min(spacing, overshoot / 2); use a larger spacing or overshoot");
  }

  // Pieces sorted by grid cell (stable, so deterministic): a cell's pieces are
  // then contiguous in memory, which the containment queries are bound by.
  const double cell = std::max(piece_edge, size / 24.0);
  {
    auto key = [&](const Piece& piece) {
      std::array<int64_t, 3> ijk;
      for (int k = 0; k < 3; ++k) ijk[k] = static_cast<int64_t>(std::floor((piece.centroid[k] - lo[k]) / cell));
      return ijk;
    };
    std::vector<std::pair<std::array<int64_t, 3>, int>> order(pieces.size());
    for (size_t e = 0; e < pieces.size(); ++e) order[e] = {key(pieces[e]), static_cast<int>(e)};
    std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<Piece> sorted;
    sorted.reserve(pieces.size());
    for (const auto& entry : order) sorted.push_back(pieces[static_cast<size_t>(entry.second)]);
    pieces = std::move(sorted);
  }

  std::vector<Candidate> candidates;
  candidates.reserve(sites.size());
  for (const Site& site : sites) candidates.push_back({site.centre, Padded(site.depth + overshoot)});

  // Which pieces some candidate contains; the gain of each candidate.
  std::vector<int64_t> gain(candidates.size(), 0);
  std::vector<char> containable(pieces.size(), 0);
  PieceGrid grid(pieces, lo, hi, cell);
  std::vector<char> cell_containable(grid.num_cells(), 0);
  for (size_t i = 0; i < candidates.size(); ++i) {
    auto whole_cell = [&](size_t flat) {
      cell_containable[flat] = 1;
      gain[i] += static_cast<int64_t>(grid.cell_size(flat));
    };
    auto one_piece = [&](int e) {
      containable[static_cast<size_t>(e)] = 1;
      ++gain[i];
    };
    grid.Visit(candidates[i].centre, candidates[i].radius, whole_cell, one_piece);
  }
  for (size_t e = 0; e < pieces.size(); ++e) {
    if (cell_containable[grid.cell_of(static_cast<int>(e))]) containable[e] = 1;
  }

  // A piece no candidate contains (near a sharp corner, or on an open sheet)
  // gets a sphere of radius overshoot at its centroid: its corners are at most
  // 2/3 of its longest edge (<= overshoot / 2) away, so the sphere holds it.
  const size_t first_fallback = candidates.size();
  for (size_t e = 0; e < pieces.size(); ++e) {
    if (!containable[e]) candidates.push_back({pieces[e].centroid, Padded(overshoot)});
  }
  gain.resize(candidates.size(), 0);
  for (size_t i = first_fallback; i < candidates.size(); ++i) {
    gain[i] = grid.CountContained(candidates[i].centre, candidates[i].radius);
  }

  // Lazy greedy set cover: a candidate's gain only falls as pieces get
  // covered, so a popped candidate whose fresh gain still beats the next
  // stored one is the best.
  std::priority_queue<HeapEntry> heap;
  for (size_t i = 0; i < candidates.size(); ++i) {
    if (gain[i] > 0) heap.push({gain[i], static_cast<int>(i)});
  }
  std::vector<int> members;
  while (grid.live() > 0 && static_cast<int>(out.chosen.size()) < max_spheres) {
    FLOWPLAN_DEMAND(!heap.empty());  // every piece is in some candidate
    const HeapEntry top = heap.top();
    heap.pop();
    const Candidate& candidate = candidates[static_cast<size_t>(top.candidate)];
    const int64_t now = grid.CountContained(candidate.centre, candidate.radius);
    if (now == 0) continue;
    if (!heap.empty() && HeapEntry{now, top.candidate} < heap.top()) {
      heap.push({now, top.candidate});
      continue;
    }
    members.clear();
    grid.ForEachContained(candidate.centre, candidate.radius, [&](int e) { members.push_back(e); });
    for (int e : members) grid.Remove(e);
    out.chosen.push_back(candidate);
  }
  out.leftover = grid.Live();
  return out;
}

}  // namespace

std::vector<Sphere> Cover(const Mesh& mesh, const CoverSettings& settings) {
  CheckSettings(settings);
  const MeshIndex index(mesh);
  const std::vector<Site> sites = Sites(mesh, index, settings);
  auto select = [&](double overshoot) {
    return Select(mesh, index, sites, overshoot, settings.spacing, settings.max_spheres);
  };
  Selection selection = select(settings.overshoot);

  // Too few spheres allowed: the least overshoot (doubled, then bisected on a
  // log scale to within 2^(1/8), about 9 %) whose greedy cover fits. This
  // spreads the excess over all spheres, where raising a few spheres' radii
  // for the leftovers (the fallback below) would swell those few.
  if (!selection.leftover.empty()) {
    const Vec3 diagonal = Vec3(index.upper()) - Vec3(index.lower());
    double fails = settings.overshoot, fits = settings.overshoot;
    Selection fitting;
    for (int doubling = 0; doubling < 64; ++doubling) {
      fits *= 2.0;
      fitting = select(fits);
      if (fitting.leftover.empty()) break;
      fails = fits;
      if (fits > 4.0 * Norm(diagonal) + 1.0) break;  // cannot happen: one sphere then holds everything
    }
    if (fitting.leftover.empty()) {
      for (int step = 0; step < 3; ++step) {
        const double middle = std::sqrt(fails * fits);
        Selection trial = select(middle);
        if (trial.leftover.empty()) {
          fits = middle;
          fitting = std::move(trial);
        } else {
          fails = middle;
        }
      }
    }
    selection = std::move(fitting);
  }
  std::vector<Piece>& pieces = selection.pieces;
  std::vector<Candidate>& chosen = selection.chosen;

  // Still out of spheres: each leftover piece raises the radius that grows least.
  if (!selection.leftover.empty()) {
    std::vector<double> raised(chosen.size());
    for (size_t j = 0; j < chosen.size(); ++j) raised[j] = chosen[j].radius;
    for (int e : selection.leftover) {
      const Piece& piece = pieces[static_cast<size_t>(e)];
      size_t best = 0;
      double best_need = INFINITY, best_growth = INFINITY;
      for (size_t j = 0; j < chosen.size(); ++j) {
        const double need = FarthestCorner(piece, chosen[j].centre);
        if (need - chosen[j].radius < best_growth) {
          best_growth = need - chosen[j].radius;
          best_need = need;
          best = j;
        }
      }
      raised[best] = std::max(raised[best], Padded(best_need));
    }
    for (size_t j = 0; j < chosen.size(); ++j) chosen[j].radius = raised[j];
  }

  // Which chosen spheres contain each piece (CSR: piece -> spheres).
  auto containing = [&](std::vector<int>& offsets, std::vector<int>& spheres, const std::vector<char>& alive) {
    offsets.assign(pieces.size() + 1, 0);
    spheres.clear();
    for (size_t e = 0; e < pieces.size(); ++e) {
      for (size_t j = 0; j < chosen.size(); ++j) {
        if (alive[j] && Contains(chosen[j].centre, chosen[j].radius, pieces[e])) spheres.push_back(static_cast<int>(j));
      }
      offsets[e + 1] = static_cast<int>(spheres.size());
    }
  };
  std::vector<char> alive(chosen.size(), 1);
  std::vector<int> offsets, spheres_of;
  containing(offsets, spheres_of, alive);

  // Drop spheres whose pieces all lie in another sphere too, the latest chosen first.
  {
    std::vector<int> count(pieces.size());
    std::vector<std::vector<int>> pieces_of(chosen.size());
    for (size_t e = 0; e < pieces.size(); ++e) {
      count[e] = offsets[e + 1] - offsets[e];
      FLOWPLAN_DEMAND(count[e] > 0);
      for (int k = offsets[e]; k < offsets[e + 1]; ++k) {
        pieces_of[static_cast<size_t>(spheres_of[k])].push_back(static_cast<int>(e));
      }
    }
    for (size_t j = chosen.size(); j-- > 0;) {
      const bool redundant = std::all_of(pieces_of[j].begin(), pieces_of[j].end(),
                                         [&](int e) { return count[static_cast<size_t>(e)] >= 2; });
      if (!redundant) continue;
      alive[j] = 0;
      for (int e : pieces_of[j]) --count[static_cast<size_t>(e)];
    }
  }

  // Tighten: each piece goes to the sphere it sits deepest in; radii shrink to fit.
  for (int round = 0; round < 3; ++round) {
    if (round > 0) containing(offsets, spheres_of, alive);
    std::vector<double> needed(chosen.size(), 0.0);
    std::vector<char> used(chosen.size(), 0);
    for (size_t e = 0; e < pieces.size(); ++e) {
      int best = -1;
      double best_ratio = INFINITY, best_need = 0.0;
      for (int k = offsets[e]; k < offsets[e + 1]; ++k) {
        const auto j = static_cast<size_t>(spheres_of[k]);
        if (!alive[j]) continue;
        const double need = FarthestCorner(pieces[e], chosen[j].centre);
        const double ratio = need / chosen[j].radius;
        if (ratio < best_ratio) {
          best_ratio = ratio;
          best_need = need;
          best = static_cast<int>(j);
        }
      }
      FLOWPLAN_DEMAND(best >= 0);
      needed[static_cast<size_t>(best)] = std::max(needed[static_cast<size_t>(best)], best_need);
      used[static_cast<size_t>(best)] = 1;
    }
    for (size_t j = 0; j < chosen.size(); ++j) {
      if (!alive[j]) continue;
      if (!used[j]) {
        alive[j] = 0;
        continue;
      }
      chosen[j].radius = std::min(chosen[j].radius, Padded(needed[j]));
    }
  }

  std::vector<Sphere> result;
  for (size_t j = 0; j < chosen.size(); ++j) {
    if (alive[j]) result.push_back({chosen[j].centre.array(), chosen[j].radius});
  }

  // The promise in terms of samples: every one of SurfaceSamples(spacing, seed).
  for (const auto& sample : SurfaceSamples(mesh, settings.spacing, settings.seed)) {
    const Vec3 p(sample);
    size_t nearest = 0;
    double nearest_gap = INFINITY;
    bool covered = false;
    for (size_t j = 0; j < result.size() && !covered; ++j) {
      const double distance = Distance(p, Vec3(result[j].centre));
      covered = distance <= result[j].radius;
      if (distance - result[j].radius < nearest_gap) {
        nearest_gap = distance - result[j].radius;
        nearest = j;
      }
    }
    if (!covered) result[nearest].radius = Padded(Distance(p, Vec3(result[nearest].centre)));
  }
  return result;
}

CoverReport CheckCover(const Mesh& mesh, const std::vector<Sphere>& spheres, double spacing, uint64_t seed,
                       int64_t volume_samples) {
  if (volume_samples < 0) {
    throw Error("CheckCover: volume_samples: expected >= 0, got " + std::to_string(volume_samples));
  }
  for (size_t j = 0; j < spheres.size(); ++j) {
    const auto& s = spheres[j];
    if (!(std::isfinite(s.centre[0]) && std::isfinite(s.centre[1]) && std::isfinite(s.centre[2]) &&
          std::isfinite(s.radius) && s.radius >= 0.0)) {
      throw Error("CheckCover: sphere " + std::to_string(j) + ": expected a finite centre and radius >= 0, got radius " +
                  NumberText(s.radius));
    }
  }
  if (!(std::isfinite(spacing) && spacing > 0.0)) {
    throw Error("CheckCover: spacing: expected a positive finite length (m), got " + NumberText(spacing));
  }
  const MeshIndex index(mesh);
  CoverReport report;
  report.spheres = static_cast<int>(spheres.size());

  // Coverage on an independent sample.
  const auto samples = SurfaceSamples(mesh, spacing, StreamSeed(seed, 1));
  report.samples = static_cast<int64_t>(samples.size());
  double largest = 0.0;
  for (const auto& sample : samples) {
    const Vec3 p(sample);
    double gap = INFINITY;
    for (const auto& s : spheres) {
      gap = std::min(gap, Distance(p, Vec3(s.centre)) - s.radius);
      if (gap <= 0.0) break;
    }
    if (gap > 0.0) {
      ++report.uncovered;
      largest = std::max(largest, gap);
    }
  }
  report.largest_uncovered = largest;

  // Per sphere: the nearest surface point, and a ball around the centre that is surely inside.
  std::vector<double> sure_radius(spheres.size(), 0.0);
  std::vector<Vec3> nearest(spheres.size());
  std::vector<double> centre_distance(spheres.size());
  for (size_t j = 0; j < spheres.size(); ++j) {
    const Vec3 c(spheres[j].centre);
    centre_distance[j] = index.DistanceTo(c, &nearest[j]);
    // No surface point is nearer than centre_distance, so the winding number is the centre's throughout.
    if (index.Inside(spheres[j].centre)) sure_radius[j] = std::min(centre_distance[j], spheres[j].radius);
  }

  // Volumes by Monte Carlo over the bounding box of the spheres and the mesh.
  if (volume_samples > 0) {
    Vec3 box_lo(index.lower()), box_hi(index.upper());
    for (const auto& s : spheres) {
      const Vec3 c(s.centre), r(s.radius, s.radius, s.radius);
      box_lo = Min(box_lo, c - r);
      box_hi = Max(box_hi, c + r);
    }
    const Vec3 box = box_hi - box_lo;
    // Cells of a coarse grid far enough from the surface are inside or outside
    // as a whole (their centre's winding number holds throughout); only points
    // in cells the surface passes through need a winding number of their own.
    constexpr int kCells = 24;
    const double cell_diagonal = Norm(box) / kCells;
    std::vector<signed char> cell_state(kCells * kCells * kCells, -1);  // -1 unknown, 0 out, 1 in, 2 mixed
    auto inside = [&](const Vec3& q) {
      int ijk[3];
      for (int k = 0; k < 3; ++k) {
        ijk[k] = box[k] > 0.0 ? std::clamp(static_cast<int>((q[k] - box_lo[k]) / box[k] * kCells), 0, kCells - 1) : 0;
      }
      signed char& state = cell_state[(ijk[0] * kCells + ijk[1]) * kCells + ijk[2]];
      if (state < 0) {
        const Vec3 centre = box_lo + Vec3((ijk[0] + 0.5) * box.x / kCells, (ijk[1] + 0.5) * box.y / kCells,
                                          (ijk[2] + 0.5) * box.z / kCells);
        state = index.DistanceTo(centre) > 0.5 * cell_diagonal
                    ? static_cast<signed char>(std::abs(index.WindingNumberAt(centre)) > 0.5)
                    : 2;
      }
      return state == 2 ? std::abs(index.WindingNumberAt(q)) > 0.5 : state == 1;
    };
    Rng rng(StreamSeed(seed, 2));
    int64_t in_mesh = 0, in_union = 0, outside = 0;
    for (int64_t n = 0; n < volume_samples; ++n) {
      const Vec3 q = box_lo + Vec3(rng.Uniform() * box.x, rng.Uniform() * box.y, rng.Uniform() * box.z);
      bool covered = false, surely_inside = false;
      for (size_t j = 0; j < spheres.size() && !surely_inside; ++j) {
        const double d2 = SquaredDistance(q, Vec3(spheres[j].centre));
        if (d2 <= spheres[j].radius * spheres[j].radius) covered = true;
        if (d2 < sure_radius[j] * sure_radius[j]) surely_inside = true;
      }
      const bool in = surely_inside || inside(q);
      in_mesh += in;
      in_union += covered;
      outside += covered && !in;
    }
    const double scale = box.x * box.y * box.z / static_cast<double>(volume_samples);
    report.mesh_volume = scale * static_cast<double>(in_mesh);
    report.union_volume = scale * static_cast<double>(in_union);
    report.outside_volume = scale * static_cast<double>(outside);
    report.overshoot_ratio = report.mesh_volume > 0.0 ? report.outside_volume / report.mesh_volume : INFINITY;
  } else {
    report.mesh_volume = report.union_volume = report.outside_volume = report.overshoot_ratio = NAN;
  }

  // How far the spheres reach outside: their boundary points outside the mesh.
  constexpr int kDirections = 256;
  std::vector<Vec3> directions;
  for (int i = 0; i < kDirections; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / kDirections;
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double angle = i * M_PI * (3.0 - std::sqrt(5.0));
    directions.emplace_back(rho * std::cos(angle), rho * std::sin(angle), z);
  }
  for (size_t j = 0; j < spheres.size(); ++j) {
    const Vec3 c(spheres[j].centre);
    const double r = spheres[j].radius;
    if (!(r > 0.0)) continue;
    std::vector<Vec3> towards = directions;
    if (centre_distance[j] > 0.0) {
      const Vec3 to_surface = (nearest[j] - c) * (1.0 / centre_distance[j]);
      towards.push_back(to_surface);
      towards.push_back(-to_surface);
    }
    for (const Vec3& u : towards) {
      const Vec3 x = c + u * r;
      if (std::abs(index.WindingNumberAt(x)) > 0.5) continue;
      report.largest_outside = std::max(report.largest_outside, index.DistanceTo(x));
    }
  }
  return report;
}

}  // namespace flowplan::spheres
