// borders: the halo plan of a sub-step (mpi/halo.hpp). One pass over the own particles for the
// border, O(border x the slabs within reach of each) to route, then one exchange.
#include "mpi/halo.hpp"

namespace particle::detail::mpi {

void Halo::build(LocalParticles& mine, const Slabs& slabs, double reach) {
  const int ranks = rank_count(), me = this_rank();
  owned_ = mine.owned();
  // Routes grouped by destination: count first, then place.
  send_counts_.assign(static_cast<std::size_t>(ranks), 0);
  if (ranks == 1) {  // no other slab to reach: no route, no message
    sources_.clear();
    receive_counts_.assign(1, 0);
    return;
  }
  // The border first: near() is this slab alone wherever x - reach and x + reach are both in
  // it (the same comparisons as owner()'s), which one pass of two comparisons a slot finds.
  const Slabs::Interval region = slabs.region(me);
  border_.clear();
  for (std::size_t slot = 0; slot < owned_; ++slot) {
    const double x = mine.x[slot];
    if (!(x - reach >= region.lo && x + reach < region.hi))
      border_.push_back(static_cast<std::uint32_t>(slot));
  }
  const auto for_each_route = [&](auto&& route) {
    for (const std::uint32_t slot : border_) {
      const auto [first, last] = slabs.near(mine.x[slot], reach);
      for (int rank = first; rank <= last; ++rank)
        if (rank != me) route(rank, slot);
    }
  };
  for_each_route([&](int rank, std::size_t) { ++send_counts_[static_cast<std::size_t>(rank)]; });
  std::vector<int> at = displacements(send_counts_);
  sources_.resize(static_cast<std::size_t>(at.back() + send_counts_.back()));
  for_each_route([&](int rank, std::size_t slot) {
    sources_[static_cast<std::size_t>(at[static_cast<std::size_t>(rank)]++)] =
        static_cast<std::uint32_t>(slot);
  });

  std::vector<Copy> sent(sources_.size()), received;
  for (std::size_t k = 0; k < sources_.size(); ++k) sent[k] = mine.copy(sources_[k]);
  receive_counts_ = all_to_all(sent, send_counts_, received);
  tally().halo_particles += received.size();
  for (const Copy& c : received) mine.add_halo(c);
}

}  // namespace particle::detail::mpi
