#include "checkpoints/checkpoint.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/format.h"

namespace flowplan::checkpoints {
namespace {

using torch::serialize::InputArchive;
using torch::serialize::OutputArchive;

InputArchive OpenArchive(const std::string& path, const torch::Device& device = torch::kCPU) {
  {
    std::FILE* probe = std::fopen(path.c_str(), "rb");
    if (probe == nullptr) throw Error(path + ": cannot open checkpoint: no such file or not readable");
    std::fclose(probe);
  }
  InputArchive archive;
  try {
    archive.load_from(path, device);
  } catch (const c10::Error& e) {
    throw Error(path + ": not a readable checkpoint (truncated or foreign file): " +
                FirstLine(e.what_without_backtrace()));
  }
  c10::IValue format;
  if (!archive.try_read("format", format) || !format.isString() || format.toStringRef() != kCheckpointFormatName) {
    throw Error(path + ": not a flowplan checkpoint (no \"format\": \"" + kCheckpointFormatName + "\" entry)");
  }
  c10::IValue version;
  if (!archive.try_read("format_version", version) || !version.isInt() ||
      version.toInt() != kCheckpointFormatVersion) {
    throw Error(path + ": checkpoint format_version " + (version.isInt() ? std::to_string(version.toInt()) : "?") +
                " is not supported (this build reads version " + std::to_string(kCheckpointFormatVersion) + ")");
  }
  return archive;
}

c10::IValue Read(InputArchive& archive, const std::string& path, const std::string& key) {
  c10::IValue value;
  if (!archive.try_read(key, value)) throw Error(path + ": checkpoint has no entry \"" + key + "\"");
  return value;
}

torch::Tensor ReadTensor(InputArchive& archive, const std::string& path, const std::string& key) {
  torch::Tensor value;
  if (!archive.try_read(key, value)) throw Error(path + ": checkpoint has no tensor \"" + key + "\"");
  return value;
}

}  // namespace

void SaveCheckpoint(const std::string& path, const CheckpointHeader& header, const CheckpointModules& modules) {
  OutputArchive archive;
  archive.write("format", c10::IValue(std::string(kCheckpointFormatName)));
  archive.write("format_version", c10::IValue(kCheckpointFormatVersion));
  archive.write("step", c10::IValue(header.step));
  archive.write("config", c10::IValue(header.config_yaml));
  archive.write("env", c10::IValue(header.trajectory.env));
  archive.write("dt", c10::IValue(header.trajectory.dt));
  archive.write("horizon", c10::IValue(header.trajectory.horizon));
  archive.write("robot", c10::IValue(kinematics::RobotToYaml(header.trajectory.robot)));
  archive.write("data_fingerprint", c10::IValue(header.data_fingerprint));
  c10::List<std::string> labels;
  for (const auto& label : header.trajectory.state_labels) labels.push_back(label);
  archive.write("state_labels", c10::IValue(labels));
  archive.write("normalizer_lo", header.normalizer.lo());
  archive.write("normalizer_hi", header.normalizer.hi());
  FLOWPLAN_DEMAND(!header.rng_states.empty());
  archive.write("rng_state", header.rng_states[0]);
  // Runs with several data parts (train.data_parts) have one generator per part.
  if (header.rng_states.size() > 1) archive.write("rng_state_parts", torch::stack(header.rng_states));
  auto write_module = [&](const char* key, const torch::nn::Module* module) {
    if (module == nullptr) return;
    OutputArchive sub;
    module->save(sub);
    archive.write(key, sub);
  };
  write_module("model", modules.model);
  write_module("ema", modules.ema);
  if (modules.optimizer != nullptr) {
    OutputArchive sub;
    modules.optimizer->save(sub);
    archive.write("optimizer", sub);
  }
  AtomicFile file(path);
  try {
    archive.save_to(file.temp_path());
  } catch (const c10::Error& e) {
    throw Error(path + ": cannot write checkpoint: " + FirstLine(e.what_without_backtrace()));
  }
  file.Commit();
}

CheckpointHeader ReadCheckpointHeader(const std::string& path) {
  InputArchive archive = OpenArchive(path);
  CheckpointHeader header;
  try {
    header.step = Read(archive, path, "step").toInt();
    header.config_yaml = Read(archive, path, "config").toStringRef();
    header.trajectory.env = Read(archive, path, "env").toStringRef();
    header.trajectory.dt = Read(archive, path, "dt").toDouble();
    header.trajectory.horizon = Read(archive, path, "horizon").toInt();
    header.trajectory.robot = kinematics::RobotFromYaml(Read(archive, path, "robot").toStringRef(), path + ": entry \"robot\"");
    header.data_fingerprint = Read(archive, path, "data_fingerprint").toStringRef();
    for (const auto& label : Read(archive, path, "state_labels").toListRef()) {
      header.trajectory.state_labels.push_back(label.toStringRef());
    }
    header.normalizer = models::MinMaxNormalizer(ReadTensor(archive, path, "normalizer_lo"),
                                                 ReadTensor(archive, path, "normalizer_hi"));
    c10::IValue parts;
    if (archive.try_read("rng_state_parts", parts)) {
      if (!parts.isTensor() || parts.toTensor().dim() != 2) throw Error("\"rng_state_parts\" is not a 2-D tensor (a generator state per data part)");
      header.rng_states = parts.toTensor().unbind(0);
    } else {
      header.rng_states = {ReadTensor(archive, path, "rng_state")};
    }
  } catch (const c10::Error& e) {
    throw Error(path + ": malformed checkpoint entry: " + FirstLine(e.what_without_backtrace()));
  } catch (const Error& e) {  // e.g. a normalizer with hi <= lo
    throw Error(path + ": malformed checkpoint entry: " + e.what());
  }
  // A CPU generator's state is a flat byte tensor of a fixed size; check it
  // here so that a foreign one is named, not rejected deep inside LibTorch.
  const int64_t state_bytes = at::detail::getDefaultCPUGenerator().get_state().numel();
  const char* key = header.rng_states.size() > 1 ? "rng_state_parts" : "rng_state";
  for (const torch::Tensor& state : header.rng_states) {
    if (state.scalar_type() != torch::kUInt8 || state.dim() != 1 || state.numel() != state_bytes) {
      throw Error(path + ": malformed checkpoint entry \"" + key + "\": expected (" + std::to_string(state_bytes) +
                  ",) uint8, got " + ShapeText(state.sizes().vec()) + " " +
                  std::string(c10::toString(state.scalar_type())));
    }
  }
  return header;
}

void LoadCheckpointWeights(const std::string& path, const CheckpointModules& modules, const torch::Device& device) {
  InputArchive archive = OpenArchive(path, device);
  auto load = [&](const char* key, auto* target) {
    if (target == nullptr) return;
    InputArchive sub;
    if (!archive.try_read(key, sub)) throw Error(path + ": checkpoint has no \"" + std::string(key) + "\" weights");
    try {
      target->load(sub);
    } catch (const c10::Error& e) {
      throw Error(path + ": \"" + std::string(key) + "\" weights do not fit this model (was the config changed?): " +
                  FirstLine(e.what_without_backtrace()));
    }
  };
  // LibTorch replaces each tensor with the stored one whatever its shape, so the
  // shapes are compared after loading.
  auto load_module = [&](const char* key, torch::nn::Module* module) {
    if (module == nullptr) return;
    std::vector<std::pair<std::string, std::vector<int64_t>>> shapes;
    for (const auto& item : module->named_parameters()) shapes.emplace_back(item.key(), item.value().sizes().vec());
    for (const auto& item : module->named_buffers()) shapes.emplace_back(item.key(), item.value().sizes().vec());
    load(key, module);
    auto params = module->named_parameters();
    auto buffers = module->named_buffers();
    for (const auto& [name, shape] : shapes) {
      const torch::Tensor* now = params.find(name);
      if (now == nullptr) now = buffers.find(name);
      if (now == nullptr || now->sizes().vec() != shape) {
        throw Error(path + ": \"" + std::string(key) + "\" weight " + name + " has shape " +
                    (now ? ShapeText(now->sizes().vec()) : std::string("(missing)")) + ", the model expects " +
                    ShapeText(shape) + " (was the config changed?)");
      }
    }
  };
  load_module("model", modules.model);
  load_module("ema", modules.ema);
  load("optimizer", modules.optimizer);
}

}  // namespace flowplan::checkpoints
