#include "datasets/trajectory_dataset.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/format.h"
#include "datasets/h5.h"

namespace flowplan::datasets {
namespace {

std::vector<std::string> Split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  if (text.empty()) return parts;
  std::stringstream stream(text);
  for (std::string part; std::getline(stream, part, separator);) parts.push_back(part);
  return parts;
}

int64_t Count(const std::vector<int64_t>& shape) {
  int64_t n = 1;
  for (auto d : shape) n *= d;
  return n;
}

void ExpectShape(const std::string& file, const std::string& name, const std::vector<int64_t>& got,
                 const std::vector<int64_t>& expected) {
  if (got != expected) {
    throw Error(file + ": " + name + ": expected shape " + ShapeText(expected) + ", got " +
                ShapeText(got));
  }
}

void WritePairs(h5::File& file, const std::string& group, const EvalPairs& pairs, int64_t state_dim) {
  file.CreateGroup(group);
  const std::vector<int64_t> shape = {pairs.count(), state_dim};
  file.WriteFloat32(group + "/start", shape, pairs.start.data());
  file.WriteFloat32(group + "/goal", shape, pairs.goal.data());
  file.SetAttribute(group, "names", Join(pairs.names, ";"));
}

EvalPairs ReadPairs(const h5::File& file, const std::string& group, int64_t state_dim) {
  EvalPairs pairs;
  if (!file.Exists(group)) return pairs;
  pairs.names = Split(file.GetStringAttribute(group, "names"), ';');
  std::vector<int64_t> shape;
  pairs.start = file.ReadFloat32(group + "/start", &shape);
  ExpectShape(file.path(), group + "/start", shape, {pairs.count(), state_dim});
  pairs.goal = file.ReadFloat32(group + "/goal", &shape);
  ExpectShape(file.path(), group + "/goal", shape, {pairs.count(), state_dim});
  return pairs;
}

}  // namespace

void TrajectoryDataset::CheckConsistent(const std::string& where) const {
  auto expect = [&](const char* name, size_t got, int64_t expected) {
    if (static_cast<int64_t>(got) != expected) {
      throw Error(where + ": " + name + ": expected " + std::to_string(expected) + " values, got " +
                  std::to_string(got));
    }
  };
  const int64_t horizon = info.horizon, state_dim = info.state_dim();
  const kinematics::RobotDescription& robot = info.robot;
  expect("states", states.size(), num_episodes * horizon * state_dim);
  robot.Validate(where);
  if (robot.num_joints > state_dim) {
    throw Error(where + ": robot \"" + robot.name + "\" has " + std::to_string(robot.num_joints) +
                " joints, more than the " + std::to_string(state_dim) + " state dimensions");
  }
  expect("commanded_start", commanded_start.size(), num_episodes * point_dim);
  expect("commanded_goal", commanded_goal.size(), num_episodes * point_dim);
  expect("family", family.size(), num_episodes);
  for (const auto& [name, array] : extras) {
    // Per-step arrays: (N, T, k), as docs/dataset_format.md promises readers.
    if (array.shape.size() != 3 || array.shape[0] != num_episodes || array.shape[1] != horizon) {
      throw Error(where + ": /extras/" + name + ": expected shape (" + std::to_string(num_episodes) + ", " +
                  std::to_string(horizon) + ", k), got " + ShapeText(array.shape));
    }
    expect(name.c_str(), array.values.size(), Count(array.shape));
  }
  for (const EvalPairs* pairs : {&train_pairs, &test_pairs}) {
    expect("eval pairs", pairs->start.size(), pairs->count() * state_dim);
    expect("eval pairs", pairs->goal.size(), pairs->count() * state_dim);
  }
}

void WriteDataset(const std::string& path, const TrajectoryDataset& dataset) {
  dataset.CheckConsistent(path);
  AtomicFile target(path);
  {
    h5::File file = h5::File::Create(target.temp_path());
    file.SetAttribute("/", "format", std::string(kDatasetFormatName));
    file.SetAttribute("/", "format_version", static_cast<int64_t>(kDatasetFormatVersion));
    file.SetAttribute("/", "env", dataset.info.env);
    file.SetAttribute("/", "dt", dataset.info.dt);
    file.SetAttribute("/", "state_labels", Join(dataset.info.state_labels, ","));
    file.SetAttribute("/", "robot", kinematics::RobotToYaml(dataset.info.robot));
    file.SetAttribute("/", "config", dataset.config_yaml);
    file.SetAttribute("/", "seed", static_cast<int64_t>(dataset.seed));
    file.SetAttribute("/", "first_episode", dataset.first_episode);
    file.SetAttribute("/", "end_episode", dataset.end_episode);
    file.SetAttribute("/", "total_episodes", dataset.total_episodes);
    file.SetAttribute("/", "rejected_episodes", dataset.rejected_episodes);
    file.SetAttribute("/", "simulator_warnings", dataset.simulator_warnings);

    const int64_t n = dataset.num_episodes;
    file.WriteFloat32("/states", {n, dataset.info.horizon, dataset.info.state_dim()}, dataset.states.data());
    file.WriteFloat64("/commanded_start", {n, dataset.point_dim}, dataset.commanded_start.data());
    file.WriteFloat64("/commanded_goal", {n, dataset.point_dim}, dataset.commanded_goal.data());
    file.WriteInt32("/family", {n}, dataset.family.data());
    if (!dataset.extras.empty()) {
      file.CreateGroup("/extras");
      for (const auto& [name, array] : dataset.extras) {
        file.WriteFloat32("/extras/" + name, array.shape, array.values.data());
      }
    }
    file.CreateGroup("/eval");
    WritePairs(file, "/eval/train_pairs", dataset.train_pairs, dataset.info.state_dim());
    WritePairs(file, "/eval/test_pairs", dataset.test_pairs, dataset.info.state_dim());
    file.Close();
  }
  target.Commit();
}

namespace {

TrajectoryDataset ReadSome(const std::string& path, const std::vector<int64_t>* episodes) {
  h5::File file = h5::File::OpenReadOnly(path);
  if (!file.HasAttribute("/", "format") ||
      file.GetStringAttribute("/", "format") != kDatasetFormatName) {
    throw Error(path + ": not a flowplan trajectory file (attribute 'format' is not \"" +
                kDatasetFormatName + "\")");
  }
  const int64_t version = file.GetIntAttribute("/", "format_version");
  if (version != kDatasetFormatVersion) {
    throw Error(path + ": format_version " + std::to_string(version) + " is not supported (this build reads version " +
                std::to_string(kDatasetFormatVersion) + ")");
  }
  TrajectoryDataset dataset;
  dataset.info.env = file.GetStringAttribute("/", "env");
  dataset.info.dt = file.GetDoubleAttribute("/", "dt");
  dataset.info.state_labels = Split(file.GetStringAttribute("/", "state_labels"), ',');
  dataset.info.robot = kinematics::RobotFromYaml(file.GetStringAttribute("/", "robot"), path + ": attribute robot");
  dataset.config_yaml = file.GetStringAttribute("/", "config");
  dataset.seed = static_cast<uint64_t>(file.GetIntAttribute("/", "seed"));
  dataset.first_episode = file.GetIntAttribute("/", "first_episode");
  dataset.end_episode = file.GetIntAttribute("/", "end_episode");
  dataset.total_episodes = file.GetIntAttribute("/", "total_episodes");
  dataset.rejected_episodes = file.GetIntAttribute("/", "rejected_episodes");
  dataset.simulator_warnings = file.GetIntAttribute("/", "simulator_warnings");

  std::vector<int64_t> shape = file.Shape("/states");
  if (shape.size() != 3) {
    throw Error(path + ": /states: expected shape (N, T, D), got " + ShapeText(shape));
  }
  if (episodes != nullptr) {
    for (size_t i = 0; i < episodes->size(); ++i) {
      if ((*episodes)[i] < 0 || (*episodes)[i] >= shape[0] || (i > 0 && (*episodes)[i] <= (*episodes)[i - 1])) {
        throw Error(path + ": episode " + std::to_string((*episodes)[i]) + " is not one of its " +
                    std::to_string(shape[0]) + " episodes in ascending order");
      }
    }
  }
  dataset.states = episodes == nullptr ? file.ReadFloat32("/states", &shape)
                                       : file.ReadFloat32Rows("/states", *episodes, &shape);
  if (episodes != nullptr) shape[0] = static_cast<int64_t>(episodes->size());
  dataset.num_episodes = shape[0];
  dataset.info.horizon = shape[1];
  const int64_t n = dataset.num_episodes;
  if (static_cast<int64_t>(dataset.info.state_labels.size()) != shape[2]) {
    throw Error(path + ": attribute state_labels names " + std::to_string(dataset.info.state_labels.size()) +
                " dimensions, /states has " + std::to_string(shape[2]));
  }
  const auto bad = std::find_if(dataset.states.begin(), dataset.states.end(), [](float v) { return !std::isfinite(v); });
  if (bad != dataset.states.end()) {
    const int64_t at = bad - dataset.states.begin(), d = at % dataset.info.state_dim();
    const int64_t row = at / (dataset.info.horizon * dataset.info.state_dim());
    throw Error(path + ": /states: " + std::to_string(*bad) + " at episode " +
                std::to_string(episodes == nullptr ? row : (*episodes)[static_cast<size_t>(row)]) + ", step " +
                std::to_string(at / dataset.info.state_dim() % dataset.info.horizon) + ", dimension " + std::to_string(d) + " (" +
                dataset.info.state_labels[static_cast<size_t>(d)] + "); states must be finite");
  }
  if (episodes != nullptr) {
    dataset.train_pairs = ReadPairs(file, "/eval/train_pairs", dataset.info.state_dim());
    dataset.test_pairs = ReadPairs(file, "/eval/test_pairs", dataset.info.state_dim());
    return dataset;
  }
  dataset.commanded_start = file.ReadFloat64("/commanded_start", &shape);
  if (shape.size() != 2 || shape[0] != n) {
    throw Error(path + ": /commanded_start: expected shape (" + std::to_string(n) + ", P), got " +
                ShapeText(shape));
  }
  dataset.point_dim = shape[1];
  dataset.commanded_goal = file.ReadFloat64("/commanded_goal", &shape);
  ExpectShape(path, "/commanded_goal", shape, {n, dataset.point_dim});
  dataset.family = file.ReadInt32("/family", &shape);
  ExpectShape(path, "/family", shape, {n});
  const std::vector<std::string> extra_names =
      file.Exists("/extras") ? file.ListGroup("/extras") : std::vector<std::string>{};
  for (const std::string& name : extra_names) {
    const std::string object = "/extras/" + name;
    FloatArray array;
    array.values = file.ReadFloat32(object, &array.shape);
    dataset.extras[name] = std::move(array);
  }
  dataset.train_pairs = ReadPairs(file, "/eval/train_pairs", dataset.info.state_dim());
  dataset.test_pairs = ReadPairs(file, "/eval/test_pairs", dataset.info.state_dim());
  dataset.CheckConsistent(path);
  return dataset;
}

}  // namespace

TrajectoryDataset ReadDataset(const std::string& path) { return ReadSome(path, nullptr); }

TrajectoryDataset ReadDatasetEpisodes(const std::string& path, const std::vector<int64_t>& episodes) {
  return ReadSome(path, &episodes);
}

namespace {

class Fnv1a {
 public:
  void Bytes(const void* data, size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < size; ++i) hash_ = (hash_ ^ bytes[i]) * 0x100000001b3ULL;
  }
  void Text(const std::string& text) {
    const uint64_t size = text.size();
    Bytes(&size, sizeof(size));
    Bytes(text.data(), text.size());
  }
  template <class T>
  void Array(const std::vector<T>& values) {
    const uint64_t size = values.size();
    Bytes(&size, sizeof(size));
    Bytes(values.data(), values.size() * sizeof(T));
  }
  uint64_t hash() const { return hash_; }

 private:
  uint64_t hash_ = 0xcbf29ce484222325ULL;
};

}  // namespace

std::string DatasetFingerprint(const TrajectoryDataset& dataset) {
  Fnv1a fnv;
  fnv.Text(dataset.info.env);
  fnv.Bytes(&dataset.info.dt, sizeof(dataset.info.dt));
  fnv.Text(Join(dataset.info.state_labels, ","));
  fnv.Text(kinematics::RobotToYaml(dataset.info.robot));
  const int64_t shape[3] = {dataset.num_episodes, dataset.info.horizon, dataset.info.state_dim()};
  fnv.Bytes(shape, sizeof(shape));
  fnv.Array(dataset.states);
  for (const EvalPairs* pairs : {&dataset.train_pairs, &dataset.test_pairs}) {
    fnv.Array(pairs->start);
    fnv.Array(pairs->goal);
    fnv.Text(Join(pairs->names, ";"));
  }
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(fnv.hash()));
  return text;
}

TrajectoryDataset MergeDatasets(const std::vector<TrajectoryDataset>& shards,
                                const std::vector<std::string>& names) {
  if (shards.empty()) throw Error("merge: no input files");
  TrajectoryDataset merged = shards.front();
  merged.num_episodes = 0;
  merged.states.clear();
  merged.commanded_start.clear();
  merged.commanded_goal.clear();
  merged.family.clear();
  merged.rejected_episodes = 0;
  merged.simulator_warnings = 0;
  for (auto& [name, array] : merged.extras) {
    array.values.clear();
    array.shape[0] = 0;
  }
  for (size_t i = 0; i < shards.size(); ++i) {
    const TrajectoryDataset& shard = shards[i];
    const std::string& where = names.at(i);
    auto require = [&](bool same, const char* what) {
      if (!same) throw Error(where + ": " + what + " differs from " + names.front() + "; not a shard of the same dataset");
    };
    require(shard.info.env == merged.info.env, "env");
    require(shard.info.dt == merged.info.dt, "dt");
    require(shard.info.state_labels == merged.info.state_labels, "state_labels");
    require(kinematics::RobotToYaml(shard.info.robot) == kinematics::RobotToYaml(merged.info.robot), "robot");
    require(shard.info.horizon == merged.info.horizon && shard.info.state_dim() == merged.info.state_dim(), "/states shape");
    require(shard.point_dim == merged.point_dim, "/commanded_start shape");
    require(shard.config_yaml == merged.config_yaml, "config");
    require(shard.seed == merged.seed, "seed");
    require(shard.total_episodes == merged.total_episodes, "total_episodes");
    require(shard.train_pairs.start == merged.train_pairs.start &&
                shard.test_pairs.start == merged.test_pairs.start &&
                shard.train_pairs.goal == merged.train_pairs.goal &&
                shard.test_pairs.goal == merged.test_pairs.goal,
            "/eval pairs");
    require(shard.extras.size() == merged.extras.size(), "/extras");
    if (i > 0 && shard.first_episode != shards[i - 1].end_episode) {
      throw Error(where + ": holds episodes [" + std::to_string(shard.first_episode) + ", " +
                  std::to_string(shard.end_episode) + "), but the shard before it ends at episode " +
                  std::to_string(shards[i - 1].end_episode) + "; give the shards in order, each once");
    }
    merged.end_episode = shard.end_episode;
    merged.num_episodes += shard.num_episodes;
    merged.states.insert(merged.states.end(), shard.states.begin(), shard.states.end());
    merged.commanded_start.insert(merged.commanded_start.end(), shard.commanded_start.begin(),
                                  shard.commanded_start.end());
    merged.commanded_goal.insert(merged.commanded_goal.end(), shard.commanded_goal.begin(),
                                 shard.commanded_goal.end());
    merged.family.insert(merged.family.end(), shard.family.begin(), shard.family.end());
    merged.rejected_episodes += shard.rejected_episodes;
    merged.simulator_warnings += shard.simulator_warnings;
    for (auto& [name, array] : merged.extras) {
      auto it = shard.extras.find(name);
      require(it != shard.extras.end(), "/extras");
      std::vector<int64_t> inner(array.shape.begin() + 1, array.shape.end());
      std::vector<int64_t> shard_inner(it->second.shape.begin() + 1, it->second.shape.end());
      require(inner == shard_inner, "/extras shape");
      array.values.insert(array.values.end(), it->second.values.begin(), it->second.values.end());
      array.shape[0] += it->second.shape[0];
    }
  }
  if (shards.front().first_episode != 0 || merged.end_episode != merged.total_episodes) {
    throw Error("merge: the shards hold episodes [" + std::to_string(shards.front().first_episode) + ", " +
                std::to_string(merged.end_episode) + ") of a dataset of " + std::to_string(merged.total_episodes) +
                "; give every shard");
  }
  merged.CheckConsistent("merge");
  return merged;
}

}  // namespace flowplan::datasets
