// The declaration tables of particle/describe.hpp and their JSON form.
//
// kMetrics is the one list of metrics: psim's --metrics object, runs.csv's metric columns, the
// analysis's column groups all follow it, in this order. A row's getter reads the RunReport
// field the engine fills; nothing else needs to change for a new metric.
#include "particle/describe.hpp"

#include <array>
#include <nlohmann/json.hpp>

namespace particle {
namespace {

using Type = MetricValue::Type;
using Kind = MetricKind;

constexpr std::array kParams = {
    ParamInfo{Param::threads, "T", "--threads", "OpenMP threads"},
    ParamInfo{Param::grid, "G", "--grid", "cells per side of the grid broad phase"},
    ParamInfo{Param::slow_factor, "slow_factor", "--slow-factor",
              "K sub-steps of 1/K per time unit"},
    ParamInfo{Param::wall_stop, "wall_stop", "--wall-stop",
              "the reading of the wall stop after a collision: per-coordinate or whole-motion"},
    ParamInfo{Param::overlap, "overlap", "--overlap",
              "the reading of a pair overlapping at a sub-step's start: it collides if it "
              "approaches (approaching) or always"},
    ParamInfo{Param::ranks, "P", "",
              "MPI ranks (processes) of one run, started by a launcher (mpirun -np P), not by a "
              "psim option"},
};

// A metric of the ranks' traffic (RankTraffic), absent for a run in one process.
template <auto Field>
MetricValue of_ranks(const RunReport& r) {
  return r.ranks ? MetricValue::of((*r.ranks).*Field) : MetricValue::absent();
}

constexpr std::array kMetrics = {
    MetricInfo{"broad_phase_s", Kind::stage_time, Type::real, "s",
               "building the broad phase's structure",
               [](const RunReport& r) { return MetricValue::of(r.stages.broad_phase_s); }},
    MetricInfo{"narrow_phase_s", Kind::stage_time, Type::real, "s",
               "exact pair tests of the broad phase's pairs, plus wall candidates",
               [](const RunReport& r) { return MetricValue::of(r.stages.narrow_phase_s); }},
    MetricInfo{"order_s", Kind::stage_time, Type::real, "s", "sorting the candidates",
               [](const RunReport& r) { return MetricValue::of(r.stages.order_s); }},
    MetricInfo{"filter_s", Kind::stage_time, Type::real, "s", "one collision per particle",
               [](const RunReport& r) { return MetricValue::of(r.stages.filter_s); }},
    MetricInfo{"resolve_s", Kind::stage_time, Type::real, "s", "accepted collisions",
               [](const RunReport& r) { return MetricValue::of(r.stages.resolve_s); }},
    MetricInfo{"advance_s", Kind::stage_time, Type::real, "s", "free motion",
               [](const RunReport& r) { return MetricValue::of(r.stages.advance_s); }},
    MetricInfo{"pair_tests", Kind::counter, Type::count, "1", "pairs the narrow phase examined",
               [](const RunReport& r) { return MetricValue::of(r.counters.pair_tests); }},
    MetricInfo{"candidates", Kind::counter, Type::count, "1",
               "wall and pair candidates entering the order",
               [](const RunReport& r) { return MetricValue::of(r.counters.candidates); }},
    MetricInfo{"pair_candidates", Kind::counter, Type::count, "1",
               "of the candidates, the pairs: those that can collide within their sub-step, the "
               "pairs the scene needed tested (the same in every exact discrete engine)",
               [](const RunReport& r) { return MetricValue::of(r.counters.pair_candidates); }},
    MetricInfo{"broad_phase_builds", Kind::counter, Type::count, "1",
               "structures the broad phase built: one per sub-step where it builds afresh each "
               "(sweep, bands, grid, gpu; mpi: each rank's), fewer where it keeps one across "
               "sub-steps (cells); 0 where there is none (brute, event)",
               [](const RunReport& r) { return MetricValue::of(r.counters.broad_phase_builds); }},
    MetricInfo{"pair_collisions", Kind::counter, Type::count, "1", "accepted pair candidates",
               [](const RunReport& r) { return MetricValue::of(r.counters.pair_collisions); }},
    MetricInfo{"wall_collisions", Kind::counter, Type::count, "1",
               "accepted wall candidates (a corner counts once)",
               [](const RunReport& r) { return MetricValue::of(r.counters.wall_collisions); }},
    MetricInfo{"dropped", Kind::counter, Type::count, "1",
               "candidates the one-per-particle filter rejected",
               [](const RunReport& r) { return MetricValue::of(r.counters.dropped); }},
    MetricInfo{"overlaps", Kind::counter, Type::count, "1",
               "pairs already overlapping at a sub-step's start",
               [](const RunReport& r) { return MetricValue::of(r.counters.overlaps); }},
    MetricInfo{"receding_overlaps", Kind::counter, Type::count, "1",
               "of the overlaps, the pairs moving apart: where the two overlap readings part (0: "
               "both give this run's state; event: 0, no sub-steps)",
               [](const RunReport& r) { return MetricValue::of(r.counters.receding_overlaps); }},
    MetricInfo{"wall_stops", Kind::counter, Type::count, "1",
               "collided particles whose rest of the sub-step a wall line cut: where the two "
               "wall-stop readings part (0: both give this run's state; event: 0, no sub-steps)",
               [](const RunReport& r) { return MetricValue::of(r.counters.wall_stops); }},
    MetricInfo{"energy_initial", Kind::physics, Type::real, "mass length^2/time^2",
               "kinetic energy before the first step, unit mass",
               [](const RunReport& r) { return MetricValue::of(r.physics.energy_initial); }},
    MetricInfo{"energy_final", Kind::physics, Type::real, "mass length^2/time^2",
               "kinetic energy after the last step, unit mass",
               [](const RunReport& r) { return MetricValue::of(r.physics.energy_final); }},
    MetricInfo{"max_overlap", Kind::physics, Type::real, "s (contact distance)",
               "deepest overlap (s - distance)/s of a pair at a sub-step's start (event: of a pair "
               "it predicts, at any event; rounding only, unless the input overlaps); 0 when none",
               [](const RunReport& r) { return MetricValue::of(r.physics.max_overlap); }},
    MetricInfo{"energy_drift", Kind::physics, Type::real, "1",
               "(energy_final - energy_initial) / energy_initial, summed in a unit of the largest "
               "speed (exact where the energies underflow); 0 for a scene at rest",
               [](const RunReport& r) { return MetricValue::of(r.physics.energy_drift); }},
    MetricInfo{"wall_impulse", Kind::physics, Type::real, "mass length/time",
               "momentum given to the walls, sum of 2 |v_normal| over wall collisions (unit mass; "
               "a corner gives both components): pressure P = wall_impulse / (4 L S)",
               [](const RunReport& r) { return MetricValue::of(r.physics.wall_impulse); }},
    MetricInfo{"transfer_s", Kind::status, Type::real, "s",
               "gpu: the device's set-up (context, kernels, memory), the upload of the scene and "
               "the download of the final state, all outside wall_s; 0 for the CPU engines",
               [](const RunReport& r) { return MetricValue::of(r.transfer_s); }},
    MetricInfo{"interrupted", Kind::status, Type::flag, "1",
               "true when a stop request (SIGINT or SIGTERM to psim) ended the run before S; the "
               "state and every other metric are then those of time_reached",
               [](const RunReport& r) { return MetricValue::of(r.interrupted); }},
    MetricInfo{"time_reached", Kind::status, Type::real, "time units",
               "time of the final state: S, or where an interrupted run stopped (after a whole "
               "sub-step, a multiple of 1/K; event: at an event)",
               [](const RunReport& r) { return MetricValue::of(r.time_reached); }},
    MetricInfo{"ranks", Kind::rank, Type::count, "1", "the processes that ran the simulation",
               of_ranks<&RankTraffic::ranks>},
    MetricInfo{"nodes", Kind::rank, Type::count, "1",
               "the machines the ranks ran on: distinct names, Slurm's (SLURMD_NODENAME) inside a "
               "Slurm job, else the host's",
               of_ranks<&RankTraffic::nodes>},
    MetricInfo{"halo_particles_max", Kind::rank, Type::count, "1",
               "copies of other ranks' particles a rank received over the sub-steps, the largest "
               "over ranks",
               of_ranks<&RankTraffic::halo_particles_max>},
    MetricInfo{"halo_particles_mean", Kind::rank, Type::real, "1",
               "the same, the mean over ranks", of_ranks<&RankTraffic::halo_particles_mean>},
    MetricInfo{"bytes_sent_max", Kind::rank, Type::count, "bytes",
               "bytes a rank handed to MPI for other ranks over the sub-steps (halo copies, "
               "proposals, migrants, counts, reductions' payload), the largest over ranks",
               of_ranks<&RankTraffic::bytes_sent_max>},
    MetricInfo{"bytes_sent_mean", Kind::rank, Type::real, "bytes",
               "the same, the mean over ranks", of_ranks<&RankTraffic::bytes_sent_mean>},
    MetricInfo{"filter_rounds", Kind::rank, Type::count, "1",
               "rounds of the one-per-particle filter across ranks, summed over sub-steps (every "
               "rank runs every round)",
               of_ranks<&RankTraffic::filter_rounds>},
    MetricInfo{"comm_s_max", Kind::rank, Type::real, "s",
               "seconds a rank spent in MPI calls during the sub-steps, waiting included, the "
               "largest over ranks (the slowest rank's)",
               of_ranks<&RankTraffic::comm_s_max>},
    MetricInfo{"comm_s_mean", Kind::rank, Type::real, "s", "the same, the mean over ranks",
               of_ranks<&RankTraffic::comm_s_mean>},
    MetricInfo{"wait_s_max", Kind::rank, Type::real, "s",
               "of comm_s, seconds in the few-byte collectives that open each move (agreement, "
               "round sums, counts), where a rank waits for the last to arrive; largest over ranks",
               of_ranks<&RankTraffic::wait_s_max>},
    MetricInfo{"wait_s_mean", Kind::rank, Type::real, "s", "the same, the mean over ranks",
               of_ranks<&RankTraffic::wait_s_mean>},
};

}  // namespace

std::span<const ParamInfo> params() { return kParams; }
std::span<const MetricInfo> metrics() { return kMetrics; }

std::string_view to_string(MetricKind kind) {
  switch (kind) {
    case Kind::stage_time:
      return "stage_time";
    case Kind::counter:
      return "counter";
    case Kind::physics:
      return "physics";
    case Kind::status:
      return "status";
    case Kind::rank:
      return "rank";
  }
  return "?";
}

std::string_view section(MetricKind kind) {
  switch (kind) {
    case Kind::stage_time:
      return "stages";
    case Kind::counter:
      return "counters";
    case Kind::rank:
      return "ranks";
    default:
      return "";
  }
}

std::string_view to_string(Growth growth) { return growth == Growth::quadratic ? "N^2" : "N"; }

std::string_view to_string(MetricValue::Type type) {
  switch (type) {
    case Type::real:
      return "real";
    case Type::count:
      return "count";
    case Type::flag:
      return "flag";
  }
  return "?";
}

std::string describe_json() {
  using Json = nlohmann::ordered_json;
  Json params = Json::array(), engines_json = Json::array(), metrics_json = Json::array();
  for (const ParamInfo& p : kParams)
    params.push_back({{"key", p.key}, {"option", p.option}, {"about", p.about}});
  for (const EngineInfo& e : engines()) {
    Json uses = Json::array();
    for (const ParamInfo& p : kParams)
      if (e.uses_param(p.param)) uses.push_back(p.key);
    engines_json.push_back({{"name", e.name},
                            {"exact", e.exact},
                            {"matches_reference", e.matches_reference},
                            {"reference", e.reference},
                            {"uses", uses},
                            {"growth", to_string(e.growth)},
                            {"cost_ns", e.cost_ns},
                            {"neighbour_ns", e.neighbour_ns},
                            {"continuous_time", e.continuous_time},
                            {"about", e.about},
                            {"unavailable", engine_unavailable(e.name)}});
  }
  for (const MetricInfo& m : kMetrics)
    metrics_json.push_back({{"key", m.key},
                            {"kind", to_string(m.kind)},
                            {"section", section(m.kind)},
                            {"type", to_string(m.type)},
                            {"unit", m.unit},
                            {"about", m.about}});
  // The OpenMP this library was built with: psweep records psim's (it may be another build).
  const Json openmp = {{"version", _OPENMP}};
  return Json{
      {"params", params}, {"engines", engines_json}, {"metrics", metrics_json}, {"openmp", openmp}}
      .dump(2);
}

}  // namespace particle
