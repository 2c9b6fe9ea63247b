#pragma once
// The halo of one sub-step, built once and used by every exchange of that sub-step (LAMMPS's
// borders and forward_comm; a plan as Cabana's Halo). build() sends each own particle to every
// other rank whose slab lies within `reach` of it, and appends what arrives to this rank's slots
// as its halo, grouped by source rank; forward() then sends a value per own particle along the
// same routes, to land at the copies' slots. A particle's copies are its own values bit for bit.
//
// With reach = s + 2 max|ux| over all particles (padded), every pair that can touch within the
// sub-step and has one particle here has the other one here too: |dx| <= s + |ux_i| + |ux_j|.
// Cost: one count exchange and one exchange of 40 bytes per copy; a fast scene has a wide halo,
// up to every particle on every rank.
#include <cstdint>
#include <vector>

#include "mpi/comm.hpp"
#include "mpi/local_particles.hpp"
#include "mpi/slabs.hpp"

namespace particle::detail::mpi {

class Halo {
 public:
  // collective: the halo of `mine` (which has none on entry) for `reach`.
  void build(LocalParticles& mine, const Slabs& slabs, double reach);

  // The own particles' count when the halo was built: halo slots start there.
  std::size_t owned() const { return owned_; }

  // collective: values[slot] of every own particle sent to the ranks that hold a copy of it,
  // written there at the copy's slot. values has a slot for every own and halo particle.
  template <class T>
  void forward(T* values) const {
    forward_of([values](std::uint32_t slot) { return values[slot]; }, values);
  }
  // The same with value_of(slot) sent for each own particle that has copies: computed for those
  // alone, not for every own particle (a rank's border is a thin share of its slab).
  template <class T, class ValueOf>
  void forward_of(ValueOf&& value_of, T* values) const {
    std::vector<T> sent(sources_.size()), received;
    for (std::size_t k = 0; k < sources_.size(); ++k) sent[k] = value_of(sources_[k]);
    all_to_all(sent, send_counts_, receive_counts_, received);
    for (std::size_t k = 0; k < received.size(); ++k) values[owned_ + k] = received[k];
  }

 private:
  std::size_t owned_ = 0;
  std::vector<std::uint32_t> sources_;  // the own slot of every copy sent, grouped by destination
  std::vector<int> send_counts_;        // per destination rank
  std::vector<int> receive_counts_;     // per source rank
  std::vector<std::uint32_t>
      border_;  // build()'s scratch: the own slots within reach of another slab
};

}  // namespace particle::detail::mpi
