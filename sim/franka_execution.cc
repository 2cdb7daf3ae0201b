#include "sim/franka_execution.h"

#include <string>

#include "core/error.h"
#include "sim/arm_xml.h"

namespace flowplan::sim {
namespace {

void ReplaceOnce(std::string& text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  FLOWPLAN_DEMAND(at != std::string::npos);
  text.replace(at, from.size(), to);
}

}  // namespace

FrankaModel MakeFrankaScene(const geometry::Scene& scene, double timestep) {
  scene.Validate(3, "execution scene");
  InstallExactConvexOverlaps();  // the margin below would make cylinders overlap what they do not touch
  std::string xml = FrankaModelXml();
  // Room for contacts of every capsule with several obstacles.
  ReplaceOnce(xml, "njmax=\"64\"", "njmax=\"2000\"");
  ReplaceOnce(xml, "nconmax=\"16\"", "nconmax=\"1000\"");
  // Contacts are detected within kMeasuredDistance (margin) and act only on overlaps (gap = margin).
  const std::string common = "margin=\"" + XmlNumber(kMeasuredDistance) + "\" gap=\"" + XmlNumber(kMeasuredDistance) +
                             "\" group=\"4\" contype=\"0\" conaffinity=\"1\" rgba=\"0.8 0.2 0.2 0.5\"";
  ReplaceOnce(xml, "<worldbody>", "<worldbody>\n" + ObstacleGeomsXml(scene, common));
  FrankaModel model(xml, "Franka scene with " + std::to_string(scene.size()) + " obstacles");
  model.SetPhysics(timestep, Integrator::kEuler);
  model.EnableObstacleContacts();
  return model;
}

ExecutionDrives FrankaDrives(const FrankaModel& scene, const ExecutionConfig& config) {
  ExecutionDrives drives;
  for (int j = 0; j < kFrankaJoints; ++j) {
    drives.qpos.push_back(j);
    drives.dof.push_back(j);
    drives.effort_limit.push_back(scene.limits().torque[j]);
  }
  drives.tcp_site = scene.tcp_site();
  if (config.controller == TrackingLaw::kComputedTorque) {
    drives.UseComputedTorque(config);
    return drives;
  }
  drives.law = ExecutionDrives::Law::kJointPd;
  drives.kp.assign(config.kp.begin(), config.kp.end());
  drives.kd.assign(config.kd.begin(), config.kd.end());
  return drives;
}

}  // namespace flowplan::sim
