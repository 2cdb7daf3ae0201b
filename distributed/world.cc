#include "distributed/world.h"

#include <cerrno>
#include <cstdlib>
#include <string>

#include "core/error.h"

namespace flowplan::distributed {
namespace {

using Getenv = std::function<const char*(const char*)>;

std::optional<std::string> Variable(const Getenv& getenv, const char* name) {
  const char* value = getenv(name);
  if (value == nullptr || *value == '\0') return std::nullopt;
  return std::string(value);
}

int ParseInt(const std::string& text, const char* name, int lo, int hi) {
  errno = 0;
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (errno != 0 || end == text.c_str() || *end != '\0' || value < lo || value > hi) {
    throw Error(std::string("environment variable ") + name + "=" + text + ": expected an integer in [" +
                std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return static_cast<int>(value);
}

int Required(const Getenv& getenv, const char* name, int lo, int hi, const std::string& because) {
  const auto value = Variable(getenv, name);
  if (!value) throw Error(std::string("environment variable ") + name + " is not set (" + because + ")");
  return ParseInt(*value, name, lo, hi);
}

int Optional(const Getenv& getenv, const char* name, int lo, int hi, int fallback) {
  const auto value = Variable(getenv, name);
  return value ? ParseInt(*value, name, lo, hi) : fallback;
}

/// "2(x3),1" -> 2: Slurm's tasks-per-node list; the first node's count.
int FirstTaskCount(const std::string& text) {
  const size_t end = text.find_first_of("(,");
  return ParseInt(text.substr(0, end), "SLURM_NTASKS_PER_NODE", 1, 1 << 20);
}

void FillRendezvous(const Getenv& getenv, World& world, const char* addr_fallback) {
  auto addr = Variable(getenv, "MASTER_ADDR");
  if (!addr && addr_fallback != nullptr) addr = Variable(getenv, addr_fallback);
  if (!addr) {
    throw Error("environment variable MASTER_ADDR is not set (" + world.source + " job of " +
                std::to_string(world.size) + " processes: the host of rank 0, e.g. 127.0.0.1 on one machine)");
  }
  world.master_addr = *addr;
  world.master_port = Optional(getenv, "MASTER_PORT", 1, 65535, 29500);
}

}  // namespace

std::optional<World> WorldFromEnvironment(const Getenv& getenv) {
  World world;
  if (Variable(getenv, "WORLD_SIZE")) {
    world.source = "torchrun";
    world.size = Required(getenv, "WORLD_SIZE", 1, 1 << 20, "");
    if (world.size == 1) return std::nullopt;
    world.rank = Required(getenv, "RANK", 0, world.size - 1, "WORLD_SIZE is set");
    world.local_rank = Optional(getenv, "LOCAL_RANK", 0, world.size - 1, world.rank);
    world.local_size = Optional(getenv, "LOCAL_WORLD_SIZE", 1, world.size, world.size);
    const auto agent = Variable(getenv, "TORCHELASTIC_USE_AGENT_STORE");
    world.agent_hosts_store = agent && (*agent == "True" || *agent == "true" || *agent == "1");
    FillRendezvous(getenv, world, nullptr);
    return world;
  }
  // Inside an srun step only: a batch script or salloc shell has SLURM_NTASKS
  // and SLURM_PROCID too, but runs one process.
  if (Variable(getenv, "SLURM_STEP_NUM_TASKS")) {
    world.source = "slurm";
    world.size = Required(getenv, "SLURM_STEP_NUM_TASKS", 1, 1 << 20, "");
    if (world.size == 1) return std::nullopt;
    world.rank = Required(getenv, "SLURM_PROCID", 0, world.size - 1, "SLURM_STEP_NUM_TASKS is set");
    world.local_rank = Optional(getenv, "SLURM_LOCALID", 0, world.size - 1, 0);
    const auto per_node = Variable(getenv, "SLURM_NTASKS_PER_NODE");
    if (!per_node) {
      world.local_size = 1;
    } else {
      world.local_size = FirstTaskCount(*per_node);
    }
    FillRendezvous(getenv, world, "SLURM_LAUNCH_NODE_IPADDR");
    return world;
  }
  return std::nullopt;
}

std::optional<World> WorldFromEnvironment() {
  return WorldFromEnvironment([](const char* name) { return std::getenv(name); });
}

}  // namespace flowplan::distributed
