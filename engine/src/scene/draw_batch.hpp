#pragma once
// A batch of random placement's draws (scene/placement.cpp), sorted by cell together with the disks
// accepted before it, then decided: the sort in draw_batch_sort.cpp, the decisions in
// draw_batch_decide.cpp.
//
// Its entries: the kept disks (accepted by earlier batches, order 0, accepted) and the batch's
// draws (order 1 + the draw's place in the batch), by row of cells, then by cell in the row (the
// cells of DiskCells, as many as the one-at-a-time placement's grid had: at least s wide, so that
// every centre closer than s to a draw lies in its 3 x 3 cells, and the same cells, so the same
// pairs are tested), a cell's disks first and its draws in draw order. Per entry x and y (16
// bytes), order (4), its cell's column (2) and decision (1); per row its start, and every
// kSignpost-th cell's start (where a full index of cells took 16 MB at a million disks, whose first
// touch cost more than the searches it saves). The arrays are sized once for the largest batch and
// refilled in place, batch after batch: only the pages a batch fills are touched.
#include <algorithm>
#include <atomic>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "default_init.hpp"
#include "particle/random_scene.hpp"
#include "scene/disk_grid.hpp"

namespace particle::detail {

enum Decision : std::uint8_t { kUndecided, kAccepted, kRefused };

// Draw k's coordinates, made from its place in the generator's stream: x from number 2k, y from
// 2k + 1, as the one-at-a-time placement made them one after the other.
class Draws {
 public:
  Draws(std::uint64_t seed, double r, double L) : seed_(seed), r_(r), L_(L), span_(L - 2 * r) {}
  double x(std::uint64_t k) const { return coordinate(2 * k); }
  double y(std::uint64_t k) const { return coordinate(2 * k + 1); }

 private:
  // min(): r + u * span may round one ulp past the wall line.
  double coordinate(std::uint64_t j) const {
    Random rng(seed_);
    rng.discard(j);
    return std::min(r_ + rng.uniform() * span_, L_ - r_);
  }

  std::uint64_t seed_;
  double r_, L_, span_;
};

class DrawBatch {
 public:
  // Room for `capacity` entries.
  DrawBatch(const DiskCells& cells, std::size_t capacity);

  // Room for a batch's draws beside `kept` disks.
  std::size_t room(std::size_t kept) const { return x_.size() - kept; }
  // Draws [first, first + count) with the disks accepted so far (those of the last batch).
  void sort(const Draws& draws, std::uint64_t first, std::size_t count, int threads);
  // Decides the batch's draws: by_order[1 + m] that of draw first + m (by_order[0] takes the kept
  // disks').
  void decide(int threads, std::uint8_t* by_order);

 private:
  // Two entries past the last stand for none (refused) and for more than two (undecided) of a
  // draw's earlier entries closer than s.
  static constexpr std::size_t kPadding = 2;
  static constexpr std::size_t kSignpost = 16;

  // the sort (draw_batch_sort.cpp)
  struct Rows;
  struct RowScratch;
  template <class To>
  void rows_of(const Draws& draws, std::uint64_t first, std::size_t from, std::size_t to,
               const To& to_row) const;
  std::vector<std::uint32_t> keep_accepted();
  void sort_row(std::size_t cy, const Rows& rows, RowScratch& scratch);

  // the decisions (draw_batch_decide.cpp)
  struct Undecided;
  std::uint32_t first_in(std::size_t cy, std::uint32_t column) const;
  void find_earlier(std::size_t cy, std::uint32_t* row_earlier) const;
  std::uint8_t judge(std::uint32_t a, std::uint32_t b) const;
  std::uint8_t judge_by_cells(std::size_t p) const;
  void judge_again(std::vector<Undecided>& undecided, std::uint8_t* by_order);
  void sweep(std::size_t row_from, std::size_t row_to, std::uint8_t* by_order,
             std::vector<Undecided>& left);

  std::size_t signposts_a_row() const { return (g_ + 1) / kSignpost + 1; }
  std::uint32_t none() const { return static_cast<std::uint32_t>(size_); }
  std::uint32_t more() const { return static_cast<std::uint32_t>(size_ + 1); }
  // Threads deciding neighbouring rows read and write each other's decisions: atomic bytes.
  std::uint8_t decision(std::size_t p) const {
    return std::atomic_ref<std::uint8_t>(decisions_[p]).load(std::memory_order_relaxed);
  }
  void decide(std::size_t p, std::uint8_t d) {
    std::atomic_ref<std::uint8_t>(decisions_[p]).store(d, std::memory_order_relaxed);
  }

  const DiskCells& cells_;
  std::size_t g_;
  std::vector<std::uint32_t>
      row_starts_;  // row cy's entries: [row_starts_[cy], row_starts_[cy + 1])
  // Row cy's first entry in cell kSignpost * k or past it: signposts_[cy * signposts_a_row() + k].
  std::vector<std::uint32_t> signposts_;
  std::size_t size_ = 0;
  // Written before read: Uninitialized, so only the pages a batch fills are touched.
  Uninitialized<double> x_, y_;
  Uninitialized<std::uint32_t> order_;
  Uninitialized<std::uint16_t> column_;
  mutable Uninitialized<std::uint8_t> decisions_;  // C++20's atomic_ref takes no const to load
};

}  // namespace particle::detail
