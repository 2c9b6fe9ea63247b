#pragma once
// The decomposition of the box among ranks: slabs along x of equal width, slab k owned by rank k.
// Slabs rather than blocks: a particle's region is one coordinate's, a rank has two neighbours,
// and a halo is one interval per side; blocks would cut the halo's volume at large P and need
// only another owner() and near() here. At most one slab per contact distance s: a thinner slab
// holds less than its own halo, so further ranks would add messages and take no work (they own
// nothing and only take part in the collectives).
//
// Every rank computes the same edges from the same L, so owner() is one function everywhere: a
// particle's owner and the ranks whose halo holds it never disagree by rounding.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace particle::detail::mpi {

class Slabs {
 public:
  Slabs(double L, double s, int ranks)
      : count_(static_cast<int>(std::min<double>(ranks, std::max(1.0, std::floor(L / s))))) {
    for (int k = 1; k < count_; ++k) edges_.push_back(L * k / count_);
  }

  int count() const { return count_; }

  // The slab (and rank) that owns a centre at x: edges belong to the slab on their right.
  int owner(double x) const {
    return static_cast<int>(std::upper_bound(edges_.begin(), edges_.end(), x) - edges_.begin());
  }

  // The centres x that slab `rank` owns: lo <= x < hi (infinite at the box's ends). owner(x) ==
  // rank exactly where lo <= x < hi, with the same comparisons, so that a caller may test these
  // first and skip owner() and near() for the slab's interior.
  struct Interval {
    double lo, hi;
  };
  Interval region(int rank) const {
    const double inf = std::numeric_limits<double>::infinity();
    if (rank >= count_) return {inf, inf};  // a rank beyond the slabs owns nothing
    const auto k = static_cast<std::size_t>(rank);
    return {rank == 0 ? -inf : edges_[k - 1], k < edges_.size() ? edges_[k] : inf};
  }

  // The slabs from first to last whose region widened by `reach` on each side holds x: every rank
  // that owns a particle within reach of x. owner() is monotone, so rounding x +- reach by less
  // than the padding of the reach (broad_phase/common.hpp's padded) loses none.
  std::pair<int, int> near(double x, double reach) const {
    return {owner(x - reach), owner(x + reach)};
  }

 private:
  int count_;
  std::vector<double> edges_;  // the inner edges, increasing
};

}  // namespace particle::detail::mpi
