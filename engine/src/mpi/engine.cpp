// The MPI engine: one run over every rank of the job (docs/engines.md, "The MPI engine"). The box
// is cut into slabs along x (mpi/slabs.hpp); each rank owns the particles in its slab at the start
// of a sub-step, and runs the model's sub-step on them with the moves between ranks named:
//  1. agree: the largest |ux| over all particles, and whether any rank was asked to stop (one
//     maximum over ranks);
//  2. borders: the halo, every particle within s + 2 max|ux| of another slab (mpi/halo.hpp);
//  3. candidates: own wall candidates and every pair with an own particle (mpi/pair_search.hpp)
//     on T threads; those whose particles are own and in no other candidate set apart (an own
//     particle's candidates are all here, so the filter accepts such a one wherever it stands),
//     the others in the total order by the particles' ids (step/order.cpp's split_contested);
//  4. the filter in rounds across ranks over the contested (mpi/rounds.hpp);
//  5. resolve and advance with contact.hpp's arithmetic (a pair between two ranks is resolved on
//     both, to the same bits, and each keeps its own particle);
//  6. exchange: particles to their new owner (mpi/exchange.hpp).
// Rank 0 leads: it holds the scene, sends each rank its particles and then, at P > 1, frees the
// run's arrays (PipelineParams::release_state) until a printed time unit or the end gathers every
// particle back to it: no rank holds the whole state during the run. Bit for bit brute's: the
// same candidates, the same order, the same accepted set, the same arithmetic on the same bits.
//
// Counters as one process counts them: a candidate between two ranks counts on the owner of its
// smaller id; an overlap between two ranks is seen on both, so those count half; pair_tests are
// the tests made, crossing pairs on both ranks. Stage times and wall_s are this rank's (psim
// writes rank 0's, whose report alone has the run's counters): the halo's build is in
// broad_phase_s, the rounds' messages in filter_s, the exchange in advance_s. The ranks' traffic
// (report.ranks: halo copies, bytes, rounds, seconds in MPI and waiting) is every rank's, tallied
// in mpi/comm.hpp, as the largest and the mean.
#include "mpi/engine.hpp"

#include <mpi.h>
#include <omp.h>
#include <sched.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "broad_phase/common.hpp"
#include "contact.hpp"
#include "mpi/comm.hpp"
#include "mpi/exchange.hpp"
#include "mpi/halo.hpp"
#include "mpi/local_particles.hpp"
#include "mpi/memory.hpp"
#include "mpi/pair_search.hpp"
#include "mpi/rounds.hpp"
#include "mpi/slabs.hpp"
#include "parallel/team.hpp"
#include "particle/processes.hpp"
#include "step/stages.hpp"

namespace particle::detail::mpi {
namespace {

class RankRun {
 public:
  RankRun(const World& run, const PipelineParams& params)
      : run_(run),
        params_(params),
        threads_(params.threads),
        team_(threads_),
        slabs_(run.L, run.s, rank_count()),
        report_(team_report(threads_)),
        found_(2 * static_cast<std::size_t>(threads_)) {
    distribute(run_, slabs_, mine_);
    released_ = this_rank() == 0 && rank_count() > 1 && params_.release_state;
    if (released_) params_.release_state();
  }

  RunReport run();

 private:
  // What every rank must agree on before a sub-step.
  struct Agreement {
    double reach;  // the halo's width
    bool stop;
  };
  // The own particles' largest |u_x|: the halo's reach.
  double largest_ux() const;
  Agreement agree(double largest_ux) const;
  template <class Lap>
  void substep(double reach, Lap&& lap);
  void find_candidates(const World& w, const World& own);
  void count(std::size_t owned);
  RankTraffic traffic() const;
  std::vector<ThreadScratch> counted();
  void free_working_memory();
  void clear_taken(std::size_t n, std::size_t owned);
  void gather();

  World run_;  // rank 0's: the run's, without arrays while released_; the others': no arrays
  const PipelineParams& params_;
  const int threads_;
  Team team_;  // every sub-step's candidate search
  const Slabs slabs_;
  RunReport report_;
  LocalParticles mine_;
  Halo halo_;
  PairSearch search_;
  // Thread t's own pairs and walls in found_[t], its own-halo pairs in found_[T + t].
  std::vector<ThreadScratch> found_;
  std::vector<Candidate> uncontested_, ordered_, accepted_;  // ordered_: the contested ones
  std::vector<std::uint8_t> uses_, taken_;                   // per slot, zero between sub-steps
  RoundsScratch rounds_;
  std::vector<std::uint32_t> leaving_;  // exchange's scratch
  std::vector<std::uint32_t> changed_;  // the own slots the last exchange changed
  std::uint64_t candidates_ = 0, pair_candidates_ = 0, dropped_ = 0;  // this rank's share (count)
  std::uint64_t wall_stops_ = 0;  // of its own particles (resolve_collision)
  bool released_ = false;
};

double RankRun::largest_ux() const {
  double most = 0;
  for (std::size_t slot = 0; slot < mine_.owned(); ++slot)
    most = std::max(most, std::fabs(mine_.ux[slot]));
  return most;
}

RankRun::Agreement RankRun::agree(double largest_ux) const {
  double local[2] = {largest_ux, stop_requested(params_.stop) ? 1.0 : 0.0}, all[2];
  const Timed timed(sizeof local, true);
  MPI_Allreduce(local, all, 2, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return {padded(run_.s + 2 * all[0], run_.L), all[1] > 0};
}

// On T threads: the own particles' cell index and wall candidates, then every pair with an own
// particle.
void RankRun::find_candidates(const World& w, const World& own) {
#pragma omp parallel num_threads(threads_)
  {
    const TeamScope scope(team_);
    const int t = omp_get_thread_num();
    ThreadScratch &mine = found_[static_cast<std::size_t>(t)],
                  &cross = found_[static_cast<std::size_t>(threads_ + t)];
    mine.clear_candidates();
    cross.clear_candidates();
    search_.prepare(own);
    search_.find_wall_candidates(own, mine);
    team_for(search_.chunks(own),
             [&](std::uint32_t c) { search_.find_pairs_in(w, own, c, mine, cross); });
    report_.cpus[static_cast<std::size_t>(t)] = sched_getcpu();
  }
}

// This rank's share of the candidates, of their pairs and of those dropped: walls (always own),
// and pairs whose smaller id (oriented: i) is own.
void RankRun::count(std::size_t owned) {
  std::uint64_t candidates = 0, kept = 0;
  for (const auto* found : {&ordered_, &uncontested_})
    for (const Candidate& c : *found)
      if (c.i < owned) {
        ++candidates;
        pair_candidates_ += !is_wall(c);
      }
  for (const Candidate& c : accepted_) kept += c.i < owned;
  candidates_ += candidates;
  dropped_ += candidates - kept;
}

// The tally of every rank's sub-steps (mpi/comm.hpp), as the largest and the mean over ranks.
RankTraffic RankRun::traffic() const {
  const Tally& t = tally();
  double most[] = {static_cast<double>(t.halo_particles), static_cast<double>(t.bytes_sent),
                   t.comm_s, t.wait_s};
  double sum[] = {most[0], most[1], most[2], most[3]};
  MPI_Allreduce(MPI_IN_PLACE, most, 4, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, sum, 4, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  const auto ranks = static_cast<double>(rank_count());
  RankTraffic r;
  r.ranks = static_cast<std::uint64_t>(rank_count());
  r.nodes = node_count();
  r.filter_rounds = t.filter_rounds;
  r.halo_particles_max = static_cast<std::uint64_t>(most[0]);
  r.halo_particles_mean = sum[0] / ranks;
  r.bytes_sent_max = static_cast<std::uint64_t>(most[1]);
  r.bytes_sent_mean = sum[1] / ranks;
  r.comm_s_max = most[2];
  r.comm_s_mean = sum[2] / ranks;
  r.wait_s_max = most[3];
  r.wait_s_mean = sum[3] / ranks;
  return r;
}

// collective: the run's candidates into the report; its tests, overlaps and deepest overlap over
// every rank, as one thread's scratch, for finish_report.
std::vector<ThreadScratch> RankRun::counted() {
  // tests, overlaps own and crossing, receding overlaps own and crossing, then this rank's shares
  std::uint64_t sums[] = {0, 0, 0, 0, 0, candidates_, dropped_, pair_candidates_, wall_stops_};
  double deepest = 0;
  for (std::size_t k = 0; k < found_.size(); ++k) {
    const bool own = k < static_cast<std::size_t>(threads_);
    sums[0] += found_[k].pair_tests;
    sums[own ? 1 : 2] += found_[k].overlaps;
    sums[own ? 3 : 4] += found_[k].receding_overlaps;
    deepest = std::max(deepest, found_[k].max_overlap);
  }
  MPI_Allreduce(MPI_IN_PLACE, sums, std::size(sums), MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &deepest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  std::vector<ThreadScratch> whole(1);
  whole[0].pair_tests = sums[0];
  // A crossing overlap is seen on both its ranks.
  whole[0].overlaps = sums[1] + sums[2] / 2;
  whole[0].receding_overlaps = sums[3] + sums[4] / 2;
  whole[0].wall_stops = sums[8];
  whole[0].max_overlap = deepest;
  report_.counters.candidates = sums[5];
  report_.counters.dropped = sums[6];
  report_.counters.pair_candidates = sums[7];
  return whole;
}

// The sub-steps' working memory, freed before the end's gather, so that rank 0 then holds the
// run's arrays beside its own particles alone (at P = 2 on the million-particle crowd, its peak
// at the gather went from 145 MB to below the distribution's 120 MB; mpi/memory.hpp).
void RankRun::free_working_memory() {
  halo_ = {};
  search_ = {};
  found_ = {};
  uncontested_ = {};
  uses_ = {};
  ordered_ = {};
  accepted_ = {};
  taken_ = {};
  rounds_ = {};
  leaving_ = {};
  return_freed_pages();
}

// taken_ back to zero where this sub-step set it: the accepted collisions' particles, and the
// halo's slots [owned, n), which the rounds' forwards wrote. O(accepted + halo), not O(slots).
void RankRun::clear_taken(std::size_t n, std::size_t owned) {
  for (const Candidate& c : accepted_) {
    taken_[c.i] = 0;
    if (!is_wall(c)) taken_[c.j] = 0;
  }
  std::fill(taken_.begin() + static_cast<std::ptrdiff_t>(owned),
            taken_.begin() + static_cast<std::ptrdiff_t>(n), 0);
}

// collective: every particle into rank 0's World (its arrays allocated again if released).
void RankRun::gather() {
  if (released_) run_ = params_.restore_state();
  collect(mine_, run_);
}

template <class Lap>
void RankRun::substep(double reach, Lap&& lap) {
  StageTimes& st = report_.stages;
  halo_.build(mine_, slabs_, reach);
  const World w = mine_.world(run_);
  World own = w;
  own.n = mine_.owned();
  search_.plan(own.n, w.n - own.n, changed_, slabs_.region(this_rank()), reach);
  lap(st.broad_phase_s);
  find_candidates(w, own);
  lap(st.narrow_phase_s);
  if (uses_.size() < w.n) uses_.resize(w.n, 0);
  if (taken_.size() < w.n) taken_.resize(w.n, 0);
  split_contested(found_, w.overlaps_collide, uses_, uncontested_, ordered_, w.id, own.n);
  lap(st.order_s);
  accept_in_rounds(ordered_, w, halo_, rounds_, taken_, accepted_);
  accept_uncontested(uncontested_, taken_, accepted_);
  count(own.n);
  lap(st.filter_s);
  // A collision with a halo particle is resolved on both ranks: each counts its own particles.
  for (const Candidate& c : accepted_) {
    const unsigned stopped = resolve_collision(w, c);
    wall_stops_ += ((stopped & kStoppedI) && c.i < own.n) + ((stopped & kStoppedJ) && c.j < own.n);
  }
  lap(st.resolve_s);
  advance_free(own, taken_, 0, own.n);
  clear_taken(w.n, own.n);
  mine_.drop_halo();
  exchange(mine_, slabs_, leaving_);
  // The slots that hold another particle now: those left (taken by arrivals or by the last own
  // particles) and those added.
  changed_ = leaving_;
  for (std::size_t slot = own.n; slot < mine_.owned(); ++slot)
    changed_.push_back(static_cast<std::uint32_t>(slot));
  lap(st.advance_s);
}

RunReport RankRun::run() {
  // Rank 0 alone writes, and its callback decides whether time units are gathered: every rank
  // must take part in a gather.
  int observed = params_.on_time_unit ? 1 : 0;
  MPI_Bcast(&observed, 1, MPI_INT, 0, MPI_COMM_WORLD);
  tally() = {};  // this run's sub-steps alone
  const bool writes = this_rank() == 0;
  Stopwatch total, watch;
  double output_s = 0, unused_s = 0;
  const auto lap = [&](double& stage) {
    if (params_.profile) watch.lap(stage);
  };
  std::int64_t substeps_done = 0;
  bool stopping = false;
  for (std::int64_t unit = 1; unit <= params_.steps && !stopping; ++unit) {
    for (int sub = 0; sub < params_.slow_factor; ++sub) {
      const Agreement agreed = agree(largest_ux());
      if (agreed.stop) {
        stopping = true;
        break;
      }
      substep(agreed.reach, lap);
      ++substeps_done;
    }
    if (observed && unit < params_.steps && !stopping) {
      watch.lap(unused_s);
      gather();
      if (writes) params_.on_time_unit(unit);
      if (released_) params_.release_state();
      watch.lap(output_s);  // printing is not simulation: kept out of wall_s
    }
  }
  const std::vector<ThreadScratch> whole = counted();
  // Each rank bins its own particles when its cells no longer serve: the most builds of a rank.
  std::uint64_t builds = search_.builds();
  MPI_Allreduce(MPI_IN_PLACE, &builds, 1, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD);
  // The end's gather is the output's, as a printed time unit's is (the cells engine's return to id
  // order is outside its wall_s too).
  watch.lap(unused_s);
  free_working_memory();
  gather();
  mine_ = {};
  if (!writes) run_.n = 0;  // no arrays to count the collisions in: rank 0 counts them
  watch.lap(output_s);
  finish_report(report_, total, output_s, substeps_done, params_, whole, run_, "mpi", builds);
  report_.ranks = traffic();
  return report_;
}

}  // namespace

namespace {

// What rank 0 tells the others before the run: the run's World without its arrays, and what
// makes every rank's loop the same.
struct RunShape {
  World world;
  std::int64_t steps;
  int slow_factor;
};

}  // namespace

RunReport lead(const World& w, const RunOptions&, const PipelineParams& params) {
  join_processes();  // a program that did not join runs as a job of one
  if (this_rank() != 0)
    throw std::logic_error("engine mpi: rank " + std::to_string(this_rank()) +
                           " follows (particle::follow); rank 0 alone runs simulate()");
  RunShape shape{w, params.steps, params.slow_factor};
  MPI_Bcast(&shape, 1, record_type<RunShape>(), 0, MPI_COMM_WORLD);
  return RankRun(w, params).run();
}

RunReport follow_leader(const PipelineParams& own) {
  join_processes();
  if (this_rank() == 0)
    throw std::logic_error("engine mpi: rank 0 leads (particle::simulate); it does not follow");
  RunShape shape;
  MPI_Bcast(&shape, 1, record_type<RunShape>(), 0, MPI_COMM_WORLD);
  World w = over_arrays(shape.world, shape.world.n, nullptr, nullptr, nullptr, nullptr, nullptr,
                        nullptr, nullptr);
  w.id = nullptr;
  PipelineParams params = own;
  params.steps = shape.steps;
  params.slow_factor = shape.slow_factor;
  return RankRun(w, params).run();
}

}  // namespace particle::detail::mpi
