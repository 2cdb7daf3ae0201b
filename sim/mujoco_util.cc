#include "sim/mujoco_util.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <mutex>

#include "core/error.h"

namespace flowplan::sim {
namespace {

// MuJoCo 2.2's XML compiler keeps global state; compile one model at a time.
std::mutex& CompilerMutex() {
  static std::mutex mutex;
  return mutex;
}

void OnMujocoError(const char* message) {
  spdlog::critical("MuJoCo error: {}", message);
  spdlog::default_logger()->flush();
  // Worker threads may still be running: skip static destructors.
  std::_Exit(EXIT_FAILURE);
}

void OnMujocoWarning(const char* message) { spdlog::debug("MuJoCo warning: {}", message); }

std::string TrimmedMessage(const char* buffer) {
  std::string text(buffer);
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  for (char& c : text) {
    if (c == '\n') c = ' ';
  }
  return text.empty() ? "unknown reason" : text;
}

}  // namespace

MjModelPtr LoadModelFromXml(const std::string& xml, const std::string& source) {
  // MuJoCo 2.2 reads XML from memory through its virtual file system. The VFS
  // is large (fixed-size name tables), so it lives on the heap.
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const char* kName = "model.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), kName, static_cast<int>(xml.size())) != 0) {
    throw Error(source + ": MuJoCo cannot load the model: virtual file system is full");
  }
  const int index = mj_findFileVFS(vfs.get(), kName);
  FLOWPLAN_DEMAND(index >= 0);
  std::copy(xml.begin(), xml.end(), static_cast<char*>(vfs->filedata[index]));
  char error[1024] = "";
  mjModel* raw = nullptr;
  {
    std::lock_guard<std::mutex> lock(CompilerMutex());
    raw = mj_loadXML(kName, vfs.get(), error, sizeof(error));
  }
  mj_deleteVFS(vfs.get());
  if (raw == nullptr) throw Error(source + ": MuJoCo cannot load the model: " + TrimmedMessage(error));
  return MjModelPtr(raw);
}

MjModelPtr LoadModelFromFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open model file");
  const std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return LoadModelFromXml(xml, path);
}

MjModelPtr CopyModel(const mjModel& m) {
  mjModel* copy = mj_copyModel(nullptr, &m);
  if (copy == nullptr) throw Error("MuJoCo: cannot copy the model (out of memory)");
  return MjModelPtr(copy);
}

MjDataPtr MakeData(const mjModel& m) {
  mjData* d = mj_makeData(&m);
  if (d == nullptr) throw Error("MuJoCo: cannot allocate simulation data (out of memory)");
  return MjDataPtr(d);
}

void InstallMujocoHandlers() {
  mju_user_error = OnMujocoError;
  mju_user_warning = OnMujocoWarning;
}

namespace {

mjfCollision original_colliders[mjNGEOMTYPES][mjNGEOMTYPES];

bool GeneralConvex(int type) { return type == mjGEOM_CYLINDER || type == mjGEOM_ELLIPSOID || type == mjGEOM_MESH; }

bool Solid(int type) { return type != mjGEOM_PLANE && type != mjGEOM_HFIELD && type < mjNGEOMTYPES; }

/// MuJoCo's collider for the pair, with every overlap it reports checked again at margin 0.
int ExactOverlapCollider(const mjModel* m, const mjData* d, mjContact* contacts, int g1, int g2, mjtNum margin) {
  const mjfCollision collide = original_colliders[m->geom_type[g1]][m->geom_type[g2]];
  const int n = collide(m, d, contacts, g1, g2, margin);
  bool overlap = false;
  for (int i = 0; i < n; ++i) overlap = overlap || contacts[i].dist < 0;
  if (!overlap || margin == 0) return n;
  mjContact exact[mjMAXCONPAIR];
  const int touching = collide(m, d, exact, g1, g2, 0);
  if (touching > 0) {
    for (int i = 0; i < touching; ++i) contacts[i] = exact[i];
    return touching;
  }
  for (int i = 0; i < n; ++i) contacts[i].dist = std::max<mjtNum>(contacts[i].dist, 0);
  return n;
}

}  // namespace

void InstallExactConvexOverlaps() {
  static std::once_flag once;
  std::call_once(once, [] {
    for (int a = 0; a < mjNGEOMTYPES; ++a) {
      for (int b = 0; b < mjNGEOMTYPES; ++b) {
        original_colliders[a][b] = mjCOLLISIONFUNC[a][b];
        const bool box_box = a == mjGEOM_BOX && b == mjGEOM_BOX;
        if (mjCOLLISIONFUNC[a][b] != nullptr && Solid(a) && Solid(b) &&
            (GeneralConvex(a) || GeneralConvex(b) || box_box)) {
          mjCOLLISIONFUNC[a][b] = &ExactOverlapCollider;
        }
      }
    }
  });
}

int64_t WarningCount(const mjData& d) {
  int64_t count = 0;
  for (int i = 0; i < mjNWARNING; ++i) count += d.warning[i].number;
  return count;
}

bool HasInstabilityWarning(const mjData& d) {
  return d.warning[mjWARN_BADQPOS].number > 0 || d.warning[mjWARN_BADQVEL].number > 0 ||
         d.warning[mjWARN_BADQACC].number > 0;
}

}  // namespace flowplan::sim
