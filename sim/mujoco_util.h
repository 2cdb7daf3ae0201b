#pragma once

// RAII ownership of MuJoCo's C objects, model loading with flowplan errors, and
// the process-wide MuJoCo error/warning handlers.

#include <mujoco/mujoco.h>

#include <cstdint>
#include <memory>
#include <string>

namespace flowplan::sim {

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};

/// An owned, compiled MuJoCo model. Shared read-only between threads once built.
using MjModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;
/// An owned MuJoCo workspace; one per thread.
using MjDataPtr = std::unique_ptr<mjData, MjDataDeleter>;

/// Compiles an MJCF model from XML text; `source` names it in errors.
/// @throws flowplan::Error "<source>: MuJoCo cannot load the model: <reason>".
MjModelPtr LoadModelFromXml(const std::string& xml, const std::string& source);

/// Compiles an MJCF file.
/// @throws flowplan::Error naming the file if it is missing or MuJoCo rejects it.
MjModelPtr LoadModelFromFile(const std::string& path);

/// A deep copy of `m`.
MjModelPtr CopyModel(const mjModel& m);

/// A fresh workspace for `m`.
/// @throws flowplan::Error if MuJoCo cannot allocate it.
MjDataPtr MakeData(const mjModel& m);

/// Installs MuJoCo error and warning handlers for this process, so that MuJoCo
/// never prints to a log file or waits for Enter. A MuJoCo error (a broken
/// model in memory, an exhausted stack) cannot be thrown through MuJoCo's C
/// frames: the handler logs one line and ends the process with exit status 1.
/// Warnings are logged at debug level; simulations count them per episode
/// with WarningCount(). Call it once at the start of main(); calling it again
/// is harmless.
void InstallMujocoHandlers();

/// Makes overlaps reported by MuJoCo's general convex collider exact. For
/// pairs with a cylinder, an ellipsoid or a mesh, MuJoCo 2.2 measures the
/// depth of both shapes grown by the contact margin, which with a margin of
/// decimetres around a thin shape reports overlaps that are not there (up to
/// 0.1 m, seen for a 12 mm bar and the arm's capsules). Its box-box collider
/// does likewise (13 cm deep for a gripper box 13 cm above a shelf board, margin
/// 0.5 m). Once installed, such a pair's overlap is confirmed with the margin set
/// to 0; an overlap that is not confirmed is reported at distance 0 (near, not
/// touching). Other pairs (spheres, capsules and boxes with one another, but
/// not box with box) keep MuJoCo's own colliders.
/// Applies to every model of the process; calling it again is harmless.
void InstallExactConvexOverlaps();

/// Number of warnings MuJoCo raised on `d` since its last mj_resetData (all kinds).
int64_t WarningCount(const mjData& d);

/// True if `d` holds a warning of an instability kind: a bad (NaN or huge)
/// position, velocity or acceleration, after which MuJoCo resets the state.
bool HasInstabilityWarning(const mjData& d);

}  // namespace flowplan::sim
