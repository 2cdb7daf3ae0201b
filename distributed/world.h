#pragma once

#include <functional>
#include <optional>
#include <string>

namespace flowplan::distributed {

/// Where this process sits in a data-parallel job, as launchers describe it.
struct World {
  int rank = 0;              // [0, size)
  int size = 1;              // number of processes
  int local_rank = 0;        // rank among the processes on this machine
  int local_size = 1;        // processes on this machine
  std::string master_addr;   // host of the rendezvous store
  int master_port = 29500;
  bool agent_hosts_store = false;  // torchrun's agent runs the store; rank 0 connects like the others
  std::string source;        // "torchrun" or "slurm", for messages
};

/// Reads the job from environment variables, through `getenv` (injectable for tests):
/// torchrun's RANK, WORLD_SIZE, LOCAL_RANK, LOCAL_WORLD_SIZE, MASTER_ADDR,
/// MASTER_PORT (and TORCHELASTIC_USE_AGENT_STORE), else, inside an srun step,
/// Slurm's SLURM_PROCID, SLURM_STEP_NUM_TASKS, SLURM_LOCALID,
/// SLURM_NTASKS_PER_NODE with MASTER_ADDR (or SLURM_LAUNCH_NODE_IPADDR) and MASTER_PORT. Returns nothing when neither
/// describes a job of more than one process.
/// @throws flowplan::Error naming the variable that is missing or malformed.
std::optional<World> WorldFromEnvironment(const std::function<const char*(const char*)>& getenv);

/// The same from the process environment.
std::optional<World> WorldFromEnvironment();

}  // namespace flowplan::distributed
