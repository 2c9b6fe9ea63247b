#pragma once
// Cell order: a run of the cells engine on many particles keeps the World's arrays in the order
// of a grid of cells (row-major, about one particle per cell) instead of id order. The cells
// broad phase counting-sorts the particles into its cells every sub-step; from id order (random
// in space) that scatter writes each record to a random place, from cell order almost every
// record lands next to the previous one (slow particles rarely change cell between sub-steps).
// On the million-particle scene the scatter was the largest single cost of the loop.
//
// The arrays are permuted in place (a temporary of one array, so peak memory grows by 12 bytes
// per particle, not by a second state) and World::id maps each slot back to its particle. Every
// stage indexes slots; the collision order's tie-breaks and a pair's orientation use the ids
// (step/order.cpp), so the run is bit for bit the id-ordered one. The arrays are back in id order
// whenever anything outside the loop reads them: around every time-unit callback and at the end
// (also when the run throws).
//
// The order is set here at the start; particles drift out of it over a long run, and the cells
// broad phase puts the arrays in the order of its own cells again when they have (cells.hpp,
// resort(): World::reorderable, set here), moving id with them, so the permutations back and
// forth below read the order of the moment.
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "parallel/private_state.hpp"
#include "particle/wait_policy.hpp"
#include "step/pipeline.hpp"
#include "world.hpp"

namespace particle::detail {

// w's particles in the order of a grid of about one particle per cell (row-major; within a cell,
// by index): slot -> particle. The mpi engine takes its own particles in this order too.
inline std::vector<std::uint32_t> cell_order(const World& w) {
  const std::size_t n = w.n;
  const auto side = static_cast<std::uint32_t>(
      std::clamp(std::floor(std::sqrt(static_cast<double>(n))), 1.0, 32768.0));
  const double inverse = side / w.L;
  const auto column = [&](double x) {
    const double c = x * inverse;
    return c <= 0 ? 0u : (c >= side - 1 ? side - 1 : static_cast<std::uint32_t>(c));
  };
  std::vector<std::uint32_t> cell(n), start(static_cast<std::size_t>(side) * side + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    cell[i] = column(w.y[i]) * side + column(w.x[i]);
    ++start[cell[i] + 1];
  }
  for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  std::vector<std::uint32_t> id(n);
  for (std::size_t i = 0; i < n; ++i) id[start[cell[i]]++] = static_cast<std::uint32_t>(i);
  return id;
}

class CellOrder {
 public:
  // Puts w's arrays in cell order; the permutations run on `threads` threads (the run's).
  CellOrder(const World& w, int threads) : w_(w), id_(cell_order(w)), threads_(threads) {
    permute(true);
  }
  ~CellOrder() { permute(false); }
  CellOrder(const CellOrder&) = delete;
  CellOrder& operator=(const CellOrder&) = delete;

  // The World over the permuted arrays.
  World world() {
    World sorted = w_;
    sorted.id = id_.data();
    sorted.reorderable = true;
    return sorted;
  }

  // Back to id order (to_cells false) or into cell order again. Over the run's threads: each
  // array's gather is a cache miss an element (the order is random in memory), and on the
  // million-particle scene the two permutations of a run took about 100 ms of one thread while
  // the others waited, a fifth of the process at T = 2.
  void permute(bool to_cells) {
    if (to_cells == in_cells_) return;
    moved_.resize(w_.n);  // one buffer for the seven arrays: zeroed and faulted in once
    std::atomic<int> arrived{0};
    const int first_cpu = sched_getcpu();
#pragma omp parallel num_threads(threads_) if (threads_ > 1)
    {
      spread_team(arrived, first_cpu);  // as the pipeline's team: a new thread starts on ours
      for_each_particle_array(w_, [&](auto* a) { move(a, to_cells); });
    }
    std::vector<std::uint64_t>().swap(moved_);  // not held through the run: peak memory
    in_cells_ = to_cells;
  }

 private:
  // team: each loop's barrier keeps the array's reads before its writes, and the buffer's
  // before the next array's.
  template <class T>
  void move(T* a, bool to_cells) {
    static_assert(sizeof(T) == sizeof(std::uint64_t));
    const std::size_t n = w_.n;
#pragma omp for schedule(static)
    for (std::size_t k = 0; k < n; ++k) {
      if (to_cells)
        moved_[k] = std::bit_cast<std::uint64_t>(a[id_[k]]);
      else
        moved_[id_[k]] = std::bit_cast<std::uint64_t>(a[k]);
    }
#pragma omp for schedule(static)
    for (std::size_t k = 0; k < n; ++k) a[k] = std::bit_cast<T>(moved_[k]);
  }

  World w_;
  std::vector<std::uint32_t> id_;  // slot -> particle
  int threads_;
  std::vector<std::uint64_t> moved_;
  bool in_cells_ = false;
};

// run_pipeline with the World in cell order, for scenes large enough to share one state (below
// kPrivateStateBelow every thread copies the state, and it fits in cache anyway) that take at
// least one sub-step (S = 0 only reads and writes the scene: the permutations would be its
// largest cost after the I/O).
template <BroadPhase Broad>
RunReport run_in_cell_order(Broad& broad, const World& w, PipelineParams params) {
  if (uses_private_state(w.n) || params.steps == 0) return run_pipeline(broad, w, params);
  CellOrder order(w, params.threads);
  if (params.on_time_unit)
    params.on_time_unit = [&order, inner = std::move(params.on_time_unit)](std::int64_t step) {
      order.permute(false);
      inner(step);
      order.permute(true);
    };
  return run_pipeline(broad, order.world(), params);
}

}  // namespace particle::detail
