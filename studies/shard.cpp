#include "studies/shard.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <numeric>
#include <ostream>
#include <stdexcept>

namespace gapflow {

std::string ShardSpec::label() const { return fmt::format("{}/{}", index, count); }

ShardSpec parse_shard(std::string_view text) {
  auto bad = [&] {
    return std::invalid_argument(fmt::format(
        "--shard '{}': expected I/K, share I of K, with 1 <= I <= K <= 100000 (e.g. --shard 3/8)", text));
  };
  const auto slash = text.find('/');
  if (slash == std::string_view::npos) throw bad();
  ShardSpec s;
  auto number = [&](std::string_view part, int& out) {
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), out);
    if (ec != std::errc() || end != part.data() + part.size()) throw bad();
  };
  number(text.substr(0, slash), s.index);
  number(text.substr(slash + 1), s.count);
  if (s.count < 1 || s.count > 100000 || s.index < 1 || s.index > s.count) throw bad();
  return s;
}

std::vector<int> assign_shards(const std::vector<Job>& jobs, int count) {
  if (count < 1) throw std::invalid_argument("assign_shards: count must be >= 1");
  double known_sum = 0;
  int known = 0;
  for (const Job& j : jobs)
    if (j.expected_cost > 0) known_sum += j.expected_cost, ++known;
  const double unknown_cost = known > 0 ? known_sum / known : 1.0;
  auto cost = [&](const Job& j) { return j.expected_cost > 0 ? j.expected_cost : unknown_cost; };

  std::vector<std::size_t> order(jobs.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const double ca = cost(jobs[a]), cb = cost(jobs[b]);
    return ca != cb ? ca > cb : jobs[a].id.key < jobs[b].id.key;
  });
  std::vector<double> load(static_cast<std::size_t>(count), 0.0);
  std::vector<int> shard_of(jobs.size(), 0);
  for (std::size_t i : order) {
    const auto least = static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    load[least] += cost(jobs[i]);
    shard_of[i] = static_cast<int>(least) + 1;
  }
  return shard_of;
}

std::vector<Job> jobs_of_shard(const std::vector<Job>& jobs, const ShardSpec& shard) {
  const std::vector<int> shard_of = assign_shards(jobs, shard.count);
  std::vector<Job> out;
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (shard_of[i] == shard.index) out.push_back(jobs[i]);
  return out;
}

std::vector<PlannedJob> plan_of(const std::vector<Job>& jobs, int count) {
  const std::vector<int> shard_of = assign_shards(jobs, count);
  std::vector<PlannedJob> out;
  for (std::size_t i = 0; i < jobs.size(); ++i)
    out.push_back({jobs[i].id, ShardSpec{shard_of[i], count}.label(), jobs[i].expected_cost});
  return out;
}

namespace {

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) out += fmt::format("\\u{:04x}", static_cast<int>(c));
        else out += c;
    }
  }
  return out + "\"";
}

}  // namespace

void write_plan(std::ostream& out, const std::vector<Job>& jobs, int count, const ShardSpec* only) {
  const std::vector<int> shard_of = assign_shards(jobs, count);
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    if (only && shard_of[i] != only->index) continue;
    const JobIdentity& id = jobs[i].id;
    std::string set;
    for (const std::string& o : jobs[i].overrides) {
      if (!set.empty()) set += ',';
      set += json_string(o);
    }
    out << fmt::format(
        "{{\"key\":\"{}\",\"shard\":\"{}/{}\",\"expected_cost\":{},\"study\":{},\"series\":{},\"point\":{},"
        "\"point_label\":{},\"axes\":{},\"model\":\"{}\",\"replicate\":{},\"run_seed\":\"{:016x}\","
        "\"scenario_hash\":\"{:016x}\",\"scenario\":{},\"set\":[{}]}}\n",
        id.key, shard_of[i], count, jobs[i].expected_cost, json_string(id.study), json_string(id.series), id.point,
        json_string(id.point_label), id.axes_json, id.model, id.replicate, id.run_seed, id.scenario_hash,
        json_string(jobs[i].scenario.string()), set);
  }
}

}  // namespace gapflow
