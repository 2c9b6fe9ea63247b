#pragma once
// The GPU engine's sub-step: the model's pipeline (docs/model.md, "The model") as a sequence of
// data-parallel stages, each a function of one index (a particle, a slot in cell order or a
// candidate) that an executor runs for every index: CUDA kernels on the device (gpu/engine.cu),
// or a plain loop on the host (gpu/host_executor.hpp), which is how `make test` checks this very
// code against `brute` on a machine without a GPU. The arithmetic is contact.hpp's, compiled for
// both; the state stays in structure-of-arrays in the executor's memory for the whole run.
//
// One sub-step:
//  1. the largest per-axis displacement (an atomic maximum of the bits: non-negative doubles
//     order as their bits), from which plan_cells picks the grid: cells at least the padded reach
//     s + 2 max|u| wide, so every pair that can touch lies in adjacent cells;
//  2. each particle's cell, a stable radix sort of (cell, particle) and the cells' ends (a
//     histogram and an inclusive scan): cell order, as the `cells` engine on the CPU;
//  3. wall candidates per particle; pair candidates over the half stencil of each slot in cell
//     order (the rest of its own row's span up to the next cell, and the row above from the cell
//     before to the cell after), so each pair is tested once, with the CPU's pair test. The
//     stencil's partners are cut into pieces of at most `piece` pairs, one thread each: in one
//     crowded cell (the 2019 default scene is one cell) slot k has N - 1 - k partners, and a
//     thread per slot left the first block with 256 x N tests, the last with almost none. The
//     root is taken only for a pair that can meet (approaching, and a real root);
//  4. the total order (t, wall before pair, i, j) by two stable radix sorts, the low key
//     (pair flag, i, j) first, then t's bits (t is in [0, 1], so its bits order as its values);
//  5. the greedy filter by rounds (step/filter_rounds.hpp, batched by Rounds below), resolve,
//     advance, as the CPU does.
//
// Executor interface (Exec): Array<T> (data(), size(), resize(n) without keeping contents),
// for_each(n, f) runs f(k) for k in [0, n), for_each_upto(most, count, f) the same for
// k < *count, a value where Exec runs that no read() brings to the host (most bounds it),
// fill(p, n, v), sort_pairs(keys, values, n, bits)
// (stable by the low `bits` of the keys), inclusive_scan(p, n), read(p) (one value to the host),
// lap(seconds) (a stage's time where profiling, else nothing).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "broad_phase/cells.hpp"
#include "contact.hpp"
#include "host_device.hpp"
#include "particle/profile.hpp"
#include "step/filter_rounds.hpp"
#include "step/pipeline.hpp"
#include "world.hpp"

namespace particle::detail::gpu {

// A non-negative double's bits, which order as its values.
PARTICLE_HD inline std::uint64_t order_bits(double v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  return bits;
}

// The grid of a sub-step: n x n cells over [0, L]^2, a particle's cell from its centre (the
// CPU's cell_column).
struct Grid {
  std::uint32_t n = 1;
  double inverse_cell = 0;
  PARTICLE_HD std::uint32_t column(double x) const { return cell_column(x, inverse_cell, n); }
  PARTICLE_HD std::uint32_t cell_of(double x, double y) const { return column(y) * n + column(x); }
};

// What the device counts over a run, read once at its end (the collisions are counted per
// particle in the World, as on the CPU).
struct Tallies {
  unsigned long long pair_tests = 0, candidates = 0, pair_candidates = 0, overlaps = 0,
                     receding_overlaps = 0, wall_stops = 0, max_overlap_bits = 0;
};

// The sort key of the total order (t, wall before pair, i, j), low half: a pair sets the top bit
// (walls first at equal t), then i and j; a wall's j (its kind) never decides, since a particle
// has one wall candidate.
PARTICLE_HD inline std::uint64_t low_key(const Candidate& c) {
  const std::uint64_t i = static_cast<std::uint64_t>(c.i) << 32;
  return is_wall(c) ? i : (std::uint64_t{1} << 63) | i | c.j;
}

// Stage functions. Each is a struct so that an executor can pass it to a kernel by value.

struct LargestDisplacement {
  World w;
  unsigned long long* bits;
  PARTICLE_HD void operator()(std::uint32_t i) const {
    store_max(bits, order_bits(axis_speed(w, i)));
  }
};

struct BinParticles {
  World w;
  Grid grid;
  std::uint64_t* cell;
  std::uint32_t* id;
  std::uint32_t* count;
  PARTICLE_HD void operator()(std::uint32_t i) const {
    const std::uint32_t c = grid.cell_of(w.x[i], w.y[i]);
    cell[i] = c;
    id[i] = i;
    fetch_add(&count[c]);
  }
};

// Appends c to the candidates if there is room; the count goes on, so the caller sees how many
// there were and retries with room for all.
PARTICLE_HD inline void append(Candidate* out, std::uint32_t* size, std::uint32_t capacity,
                               const Candidate& c) {
  const std::uint32_t k = claim(size);
  if (k < capacity) out[k] = c;
}

struct WallCandidates {
  World w;
  Candidate* out;
  std::uint32_t* size;
  std::uint32_t capacity;
  PARTICLE_HD void operator()(std::uint32_t i) const {
    const double tx = wall_axis_time(w.x[i], w.ux[i], w.lo, w.hi);
    const double ty = wall_axis_time(w.y[i], w.uy[i], w.lo, w.hi);
    const double t = std::min(tx, ty);
    if (t <= 1) append(out, size, capacity, {t, i, wall_kind(tx, ty)});
  }
};

// Slot k's partners in the half stencil: [a, a_end) in its own row, then [b, b_end) in the row
// above, read as one range of a_end - a + b_end - b partners.
struct Stencil {
  World w;
  Grid grid;
  const std::uint32_t* id;   // particles in cell order
  const std::uint32_t* end;  // per cell: one past its last slot
  struct Spans {
    std::uint32_t a, a_end, b, b_end;
    PARTICLE_HD std::uint32_t size() const { return a_end - a + (b_end - b); }
    PARTICLE_HD std::uint32_t slot(std::uint32_t m) const {  // the m-th partner's slot
      return m < a_end - a ? a + m : b + (m - (a_end - a));
    }
  };
  PARTICLE_HD std::uint32_t begin(std::uint32_t cell) const { return cell ? end[cell - 1] : 0; }
  PARTICLE_HD Spans spans(std::uint32_t k) const {
    const std::uint32_t i = id[k];
    const std::uint32_t cx = grid.column(w.x[i]), cy = grid.column(w.y[i]), n = grid.n;
    const std::uint32_t left = cx ? cx - 1 : 0, right = cx + 1 < n ? cx + 1 : n - 1;
    Spans s{k + 1, end[cy * n + right], 0, 0};
    if (cy + 1 < n) s = {s.a, s.a_end, begin((cy + 1) * n + left), end[(cy + 1) * n + right]};
    return s;
  }
};

// Per slot, how many pieces of at most `piece` partners its stencil needs (then scanned: one past
// the slot's last piece).
struct PieceCounts {
  Stencil stencil;
  std::uint32_t piece;
  std::uint32_t* pieces;
  PARTICLE_HD void operator()(std::uint32_t k) const {
    pieces[k] = (stencil.spans(k).size() + piece - 1) / piece;
  }
};

// The pair tests of one piece: the slot whose pieces hold index q (a binary search of the scanned
// counts), and its partners from (q's rank among them) x piece on.
struct PairCandidates {
  Stencil stencil;
  const std::uint32_t* pieces;  // scanned PieceCounts
  std::uint32_t slots, piece;
  Candidate* out;
  std::uint32_t* size;
  std::uint32_t capacity;
  Tallies* tallies;
  PARTICLE_HD void operator()(std::uint32_t q) const {
    std::uint32_t k = 0, high = slots;  // the first slot with pieces[k] > q
    while (k < high) {
      const std::uint32_t mid = k + (high - k) / 2;
      if (pieces[mid] > q) {
        high = mid;
      } else {
        k = mid + 1;
      }
    }
    const Stencil::Spans spans = stencil.spans(k);
    const std::uint32_t from = (q - (k ? pieces[k - 1] : 0)) * piece;
    const std::uint32_t to = from + piece < spans.size() ? from + piece : spans.size();
    const World& w = stencil.w;
    const std::uint32_t i = stencil.id[k];
    const double x = w.x[i], y = w.y[i], ux = w.ux[i], uy = w.uy[i];
    unsigned long long overlaps = 0, receding = 0, pairs = 0;
    double deepest = 0;
    for (std::uint32_t m = from; m < to; ++m) {
      const std::uint32_t j = stencil.id[spans.slot(m)];
      const PairTerms terms = pair_terms(w.x[j] - x, w.y[j] - y, w.ux[j] - ux, w.uy[j] - uy, w.s2);
      if (terms.c < 0) {  // as the CPU's note_overlap
        ++overlaps;
        deepest = std::max(deepest, overlap_depth(terms.c, w.s2));
        if (terms.b >= 0) {
          ++receding;
          if (w.overlaps_collide) {
            append(out, size, capacity, {0.0, std::min(i, j), std::max(i, j)});
            ++pairs;
          }
        }
      }
      // pair_time gives infinity to a pair that recedes or misses: skipping its root and
      // division changes nothing, and most pairs of a crowded cell are such.
      double t;
      if (terms.b < 0 && (terms.c <= 0 || terms.disc > 0) && pair_time(terms, t)) {
        append(out, size, capacity, {t, std::min(i, j), std::max(i, j)});
        ++pairs;
      }
    }
    if (to > from) add_to(&tallies->pair_tests, to - from);
    if (pairs) add_to(&tallies->pair_candidates, pairs);
    if (overlaps) {
      add_to(&tallies->overlaps, overlaps);
      store_max(&tallies->max_overlap_bits, order_bits(deepest));
    }
    if (receding) add_to(&tallies->receding_overlaps, receding);
  }
};

struct LowKeys {
  const Candidate* candidates;
  std::uint64_t* key;
  std::uint32_t* index;
  PARTICLE_HD void operator()(std::uint32_t k) const {
    key[k] = low_key(candidates[k]);
    index[k] = k;
  }
};

struct TimeKeys {
  const Candidate* candidates;
  const std::uint32_t* index;
  std::uint64_t* key;
  PARTICLE_HD void operator()(std::uint32_t k) const {
    key[k] = order_bits(candidates[index[k]].t + 0.0);  // + 0.0: a -0 orders as 0
  }
};

struct Resolve {
  World w;
  const Candidate* accepted;
  Tallies* run;  // the run's: a sub-step's tallies are added to it before the resolve
  PARTICLE_HD void operator()(std::uint32_t k) const {
    const unsigned stopped = resolve_collision(w, accepted[k]);
    if (stopped) add_to(&run->wall_stops, stopped_count(stopped));
  }
};

struct Advance {
  World w;
  const std::uint8_t* taken;
  PARTICLE_HD void operator()(std::uint32_t i) const {
    if (!taken[i]) advance_particle(w, i);
  }
};

struct Release {
  const Candidate* accepted;
  std::uint8_t* taken;
  PARTICLE_HD void operator()(std::uint32_t k) const {
    taken[accepted[k].i] = 0;
    if (!is_wall(accepted[k])) taken[accepted[k].j] = 0;
  }
};

struct Iota {
  std::uint32_t* out;
  PARTICLE_HD void operator()(std::uint32_t k) const { out[k] = k; }
};

// Between two rounds of the filter, on one thread: what the last one kept is what the next one
// has left, and a round that had candidates counts.
struct NextRound {
  std::uint32_t* left;
  std::uint32_t* next;
  unsigned long long* rounds;
  PARTICLE_HD void operator()(std::uint32_t) const {
    if (*left > 0) ++*rounds;
    *left = *next;
    *next = 0;
  }
};

// The greedy filter by rounds over `count` candidates in the total order (index: rank ->
// candidate): marks taken[] for the accepted particles and writes the accepted collisions to
// `accepted` (in no particular order: resolving them commutes); returns where Exec runs how many
// (read it, or launch on it with for_each_upto). The host learns what is left only every
// kBatch rounds, one read instead of one per round: a round launches on all `count` candidates'
// threads, those past what is left return at once, and a round with nothing left does nothing.
template <class Exec>
class Rounds {
 public:
  template <class T>
  using Array = typename Exec::template Array<T>;

  static constexpr int kBatch = 4;

  Rounds(Exec& exec, std::size_t particles) : exec_(exec) {
    best_.resize(particles);
    sizes_.resize(kSizes);
    rounds_.resize(1);
    exec_.fill(best_.data(), static_cast<std::uint32_t>(particles), kNoCandidate);
    exec_.fill(rounds_.data(), 1, 0ull);
  }

  const std::uint32_t* accept(const Candidate* candidates, const std::uint32_t* index,
                              std::uint32_t count, std::uint8_t* taken, Candidate* accepted) {
    if (remaining_.size() < count) {
      remaining_.resize(count);
      next_.resize(count);
    }
    std::uint32_t* sizes = sizes_.data();
    exec_.fill(sizes, kSizes, 0u);
    exec_.fill(&sizes[kLeft], 1, count);
    exec_.for_each(count, Iota{remaining_.data()});
    for (std::uint32_t left = count, batches = 0; left > 0; ++batches) {
      for (int r = 0; r < kBatch; ++r) {
        const std::uint32_t* now = &sizes[kLeft];
        exec_.for_each_upto(count, now,
                            Propose{candidates, index, remaining_.data(), best_.data()});
        exec_.for_each_upto(count, now,
                            Decide{candidates, index, remaining_.data(), best_.data(), taken,
                                   accepted, &sizes[kAccepted]});
        exec_.for_each_upto(count, now,
                            Sweep{candidates, index, remaining_.data(), best_.data(), taken,
                                  next_.data(), &sizes[kNext]});
        exec_.for_each(1, NextRound{&sizes[kLeft], &sizes[kNext], rounds_.data()});
        std::swap(remaining_, next_);
      }
      const std::uint32_t next = exec_.read(&sizes[kLeft]);
      // Each round accepts at least the first remaining candidate (the proof above); a batch that
      // does not is a bug, and looping on it would hang the device run.
      if (next >= left)
        throw std::logic_error("GPU filter: rounds " + std::to_string(batches * kBatch + 1) +
                               " to " + std::to_string((batches + 1) * kBatch) +
                               " made no progress (" + std::to_string(left) + " candidates left)");
      left = next;
    }
    return &sizes[kAccepted];
  }

  // The rounds that had candidates, over the run so far (a read: at the end of a run).
  std::uint64_t rounds() { return exec_.read(rounds_.data()); }

 private:
  enum : std::uint32_t { kAccepted, kNext, kLeft, kSizes };
  Exec& exec_;
  Array<std::uint32_t> best_, remaining_, next_, sizes_;
  Array<unsigned long long> rounds_;
};

// Adds a sub-step's counts to the run's, once they are final (after a retry with more room).
struct AddTallies {
  const Tallies* step;
  Tallies* run;
  std::uint32_t candidates;
  PARTICLE_HD void operator()(std::uint32_t) const {
    run->pair_tests += step->pair_tests;
    run->overlaps += step->overlaps;
    run->receding_overlaps += step->receding_overlaps;
    run->max_overlap_bits = std::max(run->max_overlap_bits, step->max_overlap_bits);
    run->candidates += candidates;
    run->pair_candidates += step->pair_candidates;
  }
};

// Partners per piece for n particles: 128, or enough that at most n pieces of n partners each
// stay below 2^32 pieces in all.
inline std::uint32_t piece_size(std::uint64_t n) {
  const std::uint64_t most = (std::uint64_t{1} << 32) - 1 - n;  // pieces the scan can count
  return static_cast<std::uint32_t>(std::max<std::uint64_t>(128, (n * n + most - 1) / most));
}

// The sub-steps of one run over a World whose arrays live where Exec runs.
template <class Exec>
class ParallelStep {
 public:
  template <class T>
  using Array = typename Exec::template Array<T>;

  ParallelStep(Exec& exec, const World& w) : exec_(exec), w_(w), rounds_(exec, w.n) {
    const auto n = static_cast<std::uint32_t>(w.n);
    cell_.resize(n);
    id_.resize(n);
    pieces_.resize(n);
    taken_.resize(n);
    accepted_.resize(n);  // one collision per particle at most
    tallies_.resize(1);
    step_tallies_.resize(1);
    largest_.resize(1);
    sizes_.resize(1);
    exec_.fill(taken_.data(), n, std::uint8_t{0});
    exec_.fill(tallies_.data(), 1, Tallies{});
    reserve(std::max<std::uint32_t>(1024, 2 * n));
  }

  // One sub-step; stage times go to st when the executor profiles.
  void substep(StageTimes& st) {
    const auto n = static_cast<std::uint32_t>(w_.n);
    std::uint32_t* size = sizes_.data();
    // 1-2. The grid and cell order.
    exec_.fill(largest_.data(), 1, 0ull);
    exec_.for_each(n, LargestDisplacement{w_, largest_.data()});
    double umax;
    const unsigned long long bits = exec_.read(largest_.data());
    std::memcpy(&umax, &bits, sizeof umax);
    SpeedStats stats;
    stats.max = umax;
    const CellsPlan plan = plan_cells(n, w_.L, w_.s, stats);
    Grid grid{static_cast<std::uint32_t>(plan.n), plan.n / w_.L};
    const std::uint32_t cells = grid.n * grid.n;
    end_.resize(cells);
    exec_.fill(end_.data(), cells, 0u);
    exec_.for_each(n, BinParticles{w_, grid, cell_.data(), id_.data(), end_.data()});
    exec_.sort_pairs(cell_.data(), id_.data(), n, std::bit_width(cells));
    exec_.inclusive_scan(end_.data(), cells);
    const Stencil stencil{w_, grid, id_.data(), end_.data()};
    exec_.for_each(n, PieceCounts{stencil, piece_, pieces_.data()});
    exec_.inclusive_scan(pieces_.data(), n);
    const std::uint32_t work = n ? exec_.read(pieces_.data() + n - 1) : 0;
    exec_.lap(st.broad_phase_s);
    // 3. Candidates, with room for all of them (the count says how many there were).
    std::uint32_t count = 0;
    for (int tries = 0;; ++tries) {
      // The count is exact, so the second try has room; a third means the count moves.
      if (tries == 3)
        throw std::logic_error("GPU candidates: " + std::to_string(count) +
                               " found after 2 retries with room for " + std::to_string(capacity_));
      exec_.fill(size, 1, 0u);
      exec_.fill(step_tallies_.data(), 1, Tallies{});
      exec_.for_each(n, WallCandidates{w_, candidates_.data(), size, capacity_});
      exec_.for_each(work, PairCandidates{stencil, pieces_.data(), n, piece_, candidates_.data(),
                                          size, capacity_, step_tallies_.data()});
      count = exec_.read(size);
      if (count <= capacity_) break;
      reserve(count + count / 4);
    }
    exec_.for_each(1, AddTallies{step_tallies_.data(), tallies_.data(), count});
    exec_.lap(st.narrow_phase_s);
    // 4. The total order.
    exec_.for_each(count, LowKeys{candidates_.data(), key_.data(), index_.data()});
    exec_.sort_pairs(key_.data(), index_.data(), count, 64);
    exec_.for_each(count, TimeKeys{candidates_.data(), index_.data(), key_.data()});
    exec_.sort_pairs(key_.data(), index_.data(), count, 63);
    exec_.lap(st.order_s);
    // 5. The filter by rounds, resolve, advance.
    const std::uint32_t* accepted =
        rounds_.accept(candidates_.data(), index_.data(), count, taken_.data(), accepted_.data());
    exec_.lap(st.filter_s);
    exec_.for_each_upto(n, accepted, Resolve{w_, accepted_.data(), tallies_.data()});
    exec_.lap(st.resolve_s);
    exec_.for_each(n, Advance{w_, taken_.data()});
    exec_.for_each_upto(n, accepted, Release{accepted_.data(), taken_.data()});
    exec_.lap(st.advance_s);
  }

  // The run's counts so far.
  Tallies tallies() { return exec_.read(tallies_.data()); }

 private:
  void reserve(std::uint32_t capacity) {
    capacity_ = capacity;
    candidates_.resize(capacity);
    index_.resize(capacity);
    key_.resize(capacity);
  }

  Exec& exec_;
  World w_;
  Rounds<Exec> rounds_;
  std::uint32_t capacity_ = 0;
  Array<std::uint64_t> cell_, key_;
  Array<std::uint32_t> id_, end_, index_, sizes_, pieces_;
  // Partners per piece: 128 (a few microseconds of a GPU thread), more where N x N / 128 pieces
  // could pass the 2^32 that the scanned counts hold (a crowded cell of millions).
  std::uint32_t piece_ = piece_size(static_cast<std::uint64_t>(w_.n));
  Array<std::uint8_t> taken_;
  Array<Candidate> candidates_, accepted_;
  Array<Tallies> tallies_, step_tallies_;
  Array<unsigned long long> largest_;
};

// A whole run on Exec: the state goes to the executor's memory once, comes back for each printed
// time unit and at the end. Exec adds upload(host World) -> its World, download(its, host) and
// warm_up() (what a first launch would otherwise pay inside the loop). wall_s is the stepping
// loop alone, up to the device's last kernel; the set-up, upload and final download are
// transfer_s.
template <class Exec>
RunReport run_parallel(Exec& exec, const World& host, const PipelineParams& params) {
  RunReport report;
  Stopwatch setup;
  const World w = exec.upload(host);
  ParallelStep<Exec> step(exec, w);
  exec.warm_up();
  setup.lap(report.transfer_s);
  Stopwatch total, watch;
  double output_s = 0, unused_s = 0;
  std::int64_t substeps_done = 0;
  bool stopping = false;
  for (std::int64_t unit = 1; unit <= params.steps && !stopping; ++unit) {
    for (int sub = 0; sub < params.slow_factor; ++sub) {
      if (stop_requested(params.stop)) {
        stopping = true;
        break;
      }
      step.substep(report.stages);
      ++substeps_done;
    }
    if (params.on_time_unit && unit < params.steps && !stopping) {
      watch.lap(unused_s);
      exec.download(w, host);
      params.on_time_unit(unit);
      watch.lap(output_s);  // printing is not simulation: kept out of wall_s
    }
  }
  // The CPU engines' report from the same counts: the device's tallies as one thread's. Reading
  // them waits for the device's last kernel: the loop ends there.
  const Tallies t = step.tallies();
  watch.lap(unused_s);
  exec.download(w, host);
  double download_s = 0;
  watch.lap(download_s);
  report.transfer_s += download_s;
  std::vector<ThreadScratch> scratch(1);
  scratch[0].pair_tests = t.pair_tests;
  scratch[0].overlaps = t.overlaps;
  scratch[0].receding_overlaps = t.receding_overlaps;
  scratch[0].wall_stops = t.wall_stops;
  std::memcpy(&scratch[0].max_overlap, &t.max_overlap_bits, sizeof(double));
  // Cell order afresh every sub-step.
  finish_report(report, total, output_s + download_s, substeps_done, params, scratch, host, "gpu",
                static_cast<std::uint64_t>(substeps_done));
  report.counters.candidates = t.candidates;
  report.counters.pair_candidates = t.pair_candidates;
  report.counters.dropped =
      t.candidates - report.counters.pair_collisions - report.counters.wall_collisions;
  report.cpus = {sched_getcpu()};
  return report;
}

}  // namespace particle::detail::gpu
