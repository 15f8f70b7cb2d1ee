#include "studies/record_pack.hpp"

#include <fmt/format.h>

#include <cstring>
#include <stdexcept>
#include <type_traits>

namespace gapflow {

namespace {

// Every field of a record, in one order, for packing and unpacking alike.
template <class R, class F>
void record_fields(R& r, F&& f) {
  f(r.model), f(r.scenario_name), f(r.scenario_hash), f(r.base_seed), f(r.replicate), f(r.run_seed);
  f(r.time_step_s), f(r.diameter_m), f(r.gap_m), f(r.distance_m), f(r.incline_rad);
  f(r.particles), f(r.passed), f(r.reinjected), f(r.perturbations), f(r.escaped), f(r.max_conservation_error);
  f(r.sim_time_s), f(r.wall_time_s), f(r.end_reason), f(r.regime), f(r.j_paper), f(r.j_flowing), f(r.j_mid);
  f(r.crossings), f(r.avalanches), f(r.clogs);
}
template <class C, class F>
void crossing_fields(C& c, F&& f) { f(c.id), f(c.t), f(c.x); }
template <class A, class F>
void avalanche_fields(A& a, F&& f) { f(a.size), f(a.t_start), f(a.t_end), f(a.first), f(a.censored); }
template <class K, class F>
void clog_fields(K& k, F&& f) { f(k.t_start), f(k.duration), f(k.censored), f(k.front_m), f(k.on_obstruction); }

struct Writer {
  std::string out;
  template <class T>
  void raw(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void operator()(const std::string& s) { raw(static_cast<std::uint64_t>(s.size())), out += s; }
  template <class T>
  void operator()(const std::optional<T>& v) {
    raw(static_cast<std::uint8_t>(v.has_value()));
    if (v) (*this)(*v);
  }
  template <class T>
  void operator()(const std::vector<T>& v) {
    raw(static_cast<std::uint64_t>(v.size()));
    for (const T& e : v) element(e);
  }
  template <class T>
  void operator()(const T& v) { raw(v); }  // numbers, bools, enums
  void element(const Crossing& c) { crossing_fields(c, *this); }
  void element(const Avalanche& a) { avalanche_fields(a, *this); }
  void element(const Clog& k) { clog_fields(k, *this); }
};

struct Reader {
  const std::string& in;
  std::size_t at = 0;
  template <class T>
  void raw(T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (in.size() - at < sizeof v) throw std::runtime_error("packed run record is truncated");
    std::memcpy(&v, in.data() + at, sizeof v);
    at += sizeof v;
  }
  void operator()(std::string& s) {
    std::uint64_t n = 0;
    raw(n);
    if (in.size() - at < n) throw std::runtime_error("packed run record is truncated");
    s.assign(in, at, n);
    at += n;
  }
  template <class T>
  void operator()(std::optional<T>& v) {
    std::uint8_t has = 0;
    raw(has);
    v.reset();
    if (has) (*this)(v.emplace());
  }
  template <class T>
  void operator()(std::vector<T>& v) {
    std::uint64_t n = 0;
    raw(n);
    if (n > in.size()) throw std::runtime_error("packed run record is damaged");
    v.assign(n, T{});
    for (T& e : v) element(e);
  }
  template <class T>
  void operator()(T& v) { raw(v); }
  void element(Crossing& c) { crossing_fields(c, *this); }
  void element(Avalanche& a) { avalanche_fields(a, *this); }
  void element(Clog& k) { clog_fields(k, *this); }
};

}  // namespace

std::string pack_record(const RunRecord& r) {
  Writer w;
  record_fields(r, w);
  return std::move(w.out);
}

RunRecord unpack_record(const std::string& bytes) {
  RunRecord r;
  Reader rd{bytes};
  record_fields(r, rd);
  if (rd.at != bytes.size()) throw std::runtime_error("packed run record has trailing bytes");
  return r;
}

bool same_results(const RunRecord& a, const RunRecord& b) {
  RunRecord x = a, y = b;
  x.wall_time_s = y.wall_time_s = 0;
  return pack_record(x) == pack_record(y);
}

std::string identity_difference(const JobIdentity& a, const JobIdentity& b) {
  auto differs = [](const char* name, const auto& x, const auto& y) {
    return x == y ? std::string() : fmt::format("{} '{}' vs '{}'", name, x, y);
  };
  for (std::string d : {differs("key", a.key, b.key), differs("study", a.study, b.study),
                        differs("series", a.series, b.series), differs("point", a.point, b.point),
                        differs("point_label", a.point_label, b.point_label), differs("model", a.model, b.model),
                        differs("replicate", a.replicate, b.replicate), differs("run_seed", a.run_seed, b.run_seed),
                        differs("scenario_hash", a.scenario_hash, b.scenario_hash)})
    if (!d.empty()) return d;
  return "";
}

}  // namespace gapflow
