#include "datasets/generator.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <regex>
#include <mutex>

#include "core/error.h"
#include "core/interrupt.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/random.h"

namespace flowplan::datasets {
namespace {

/// The rejection reasons of `records`, numbers left out, most frequent first (three at most), with their counts.
std::string CommonReasons(const std::vector<EpisodeRecord>& records) {
  static const std::regex number(R"(-?[0-9][0-9.e+-]*)");
  std::map<std::string, int64_t> counts;
  for (const EpisodeRecord& record : records) {
    if (record.rejected) ++counts[std::regex_replace(record.reject_reason, number, "#")];
  }
  std::vector<std::pair<int64_t, std::string>> ranked;
  for (const auto& [reason, n] : counts) ranked.push_back({-n, reason});
  std::sort(ranked.begin(), ranked.end());
  std::string text;
  for (size_t k = 0; k < std::min<size_t>(3, ranked.size()); ++k) {
    text += (k ? "; " : "") + std::to_string(-ranked[k].first) + " x \"" + ranked[k].second + "\"";
  }
  return text;
}

void CheckRecord(const EpisodeRecord& record, const EpisodeLayout& layout) {
  FLOWPLAN_DEMAND(static_cast<int64_t>(record.states.size()) == layout.info.horizon * layout.info.state_dim());
  FLOWPLAN_DEMAND(static_cast<int64_t>(record.commanded_start.size()) == layout.point_dim);
  FLOWPLAN_DEMAND(static_cast<int64_t>(record.commanded_goal.size()) == layout.point_dim);
  for (const auto& [name, k] : layout.extras) {
    auto it = record.extras.find(name);
    FLOWPLAN_DEMAND(it != record.extras.end());
    FLOWPLAN_DEMAND(static_cast<int64_t>(it->second.size()) == layout.info.horizon * k);
  }
}

void AppendState(const std::vector<double>& states, int64_t step, int64_t dim, std::vector<float>& out) {
  for (int64_t d = 0; d < dim; ++d) out.push_back(static_cast<float>(states[step * dim + d]));
}

}  // namespace

TrajectoryDataset GenerateDataset(const EpisodeTask& task, const GenerateOptions& options) {
  if (options.shard_count < 1 || options.shard_index < 0 || options.shard_index >= options.shard_count) {
    throw Error("--shard: expected k/n with 0 <= k < n, got " + std::to_string(options.shard_index) + "/" +
                std::to_string(options.shard_count));
  }
  const EpisodeLayout layout = task.Layout();
  const int64_t begin = options.episodes * options.shard_index / options.shard_count;
  const int64_t end = options.episodes * (options.shard_index + 1) / options.shard_count;
  const int64_t count = end - begin;
  const int64_t T = layout.info.horizon, D = layout.info.state_dim();

  std::vector<EpisodeRecord> records(static_cast<size_t>(count));
  const int threads = std::max(1, options.threads);
  std::vector<std::unique_ptr<EpisodeWorker>> workers;
  for (int w = 0; w < threads; ++w) workers.push_back(task.MakeWorker());

  ProgressMeter progress("generate " + layout.info.env, count, "episodes");
  std::atomic<int64_t> done{0};
  std::mutex progress_mutex;
  progress.Update(0);
  ParallelFor(static_cast<int>(count), threads, [&](int worker, int i) {
    ThrowIfInterrupted();
    const int64_t index = begin + i;
    records[i] = workers[worker]->Run(index, StreamSeed(options.seed, static_cast<uint64_t>(index)));
    CheckRecord(records[i], layout);
    const int64_t finished = ++done;
    if (options.show_progress) {
      std::lock_guard<std::mutex> lock(progress_mutex);
      progress.Update(finished);
    }
  });

  TrajectoryDataset dataset;
  dataset.info = layout.info;
  dataset.point_dim = layout.point_dim;
  dataset.config_yaml = options.config_yaml;
  dataset.seed = options.seed;
  dataset.first_episode = begin;
  dataset.end_episode = end;
  dataset.total_episodes = options.episodes;
  for (const auto& [name, k] : layout.extras) dataset.extras[name].shape = {0, T, k};
  for (const EpisodeRecord& record : records) {
    if (record.rejected) {
      ++dataset.rejected_episodes;
      continue;
    }
    ++dataset.num_episodes;
    dataset.simulator_warnings += record.simulator_warnings;
    for (int64_t t = 0; t < T; ++t) AppendState(record.states, t, D, dataset.states);
    dataset.commanded_start.insert(dataset.commanded_start.end(), record.commanded_start.begin(),
                                   record.commanded_start.end());
    dataset.commanded_goal.insert(dataset.commanded_goal.end(), record.commanded_goal.begin(),
                                  record.commanded_goal.end());
    dataset.family.push_back(record.family);
    for (auto& [name, array] : dataset.extras) {
      const auto& values = record.extras.at(name);
      for (double v : values) array.values.push_back(static_cast<float>(v));
      array.shape[0] += 1;
    }
  }
  if (count > 0 && dataset.num_episodes == 0) {
    throw Error("generate " + layout.info.env + ": all " + std::to_string(count) +
                " episodes were rejected (first reason: " + records.front().reject_reason + ")");
  }
  if (dataset.rejected_episodes > 0) {
    spdlog::warn("generate {}: rejected {} of {} episodes (unstable or failed rollouts); most often: {}", layout.info.env,
                 dataset.rejected_episodes, count, CommonReasons(records));
  }

  // Evaluation pairs from the noise-free nominal rollout of each family.
  const std::vector<Family> families = task.Families();
  std::vector<EpisodeRecord> nominal;
  for (size_t f = 0; f < families.size(); ++f) {
    nominal.push_back(workers[0]->RunNominal(static_cast<int>(f)));
    if (nominal.back().rejected) {  // its states would be a stopped rollout, not the family's start and goal
      throw Error("generate " + layout.info.env + ": the noise-free rollout of family " + families[f].name +
                  ", which gives the evaluation pairs, was rejected: " + nominal.back().reject_reason);
    }
  }
  auto add_pair = [&](EvalPairs& pairs, size_t from, size_t to, const std::string& name) {
    AppendState(nominal[from].states, 0, D, pairs.start);
    AppendState(nominal[to].states, T - 1, D, pairs.goal);
    pairs.names.push_back(name);
  };
  for (size_t i = 0; i < families.size(); ++i) {
    add_pair(dataset.train_pairs, i, i, families[i].name);
  }
  for (size_t i = 0; i < families.size(); ++i) {
    for (size_t j = 0; j < families.size(); ++j) {
      if (i == j) continue;
      bool connected = false;
      for (const Family& f : families) {
        connected |= (f.start == families[i].start && f.goal == families[j].goal);
      }
      if (connected) continue;
      const std::string from = families[i].name.substr(0, families[i].name.find("->"));
      const std::string to = families[j].name.substr(families[j].name.find("->") + 2);
      add_pair(dataset.test_pairs, i, j, from + "->" + to);
    }
  }
  return dataset;
}

}  // namespace flowplan::datasets
