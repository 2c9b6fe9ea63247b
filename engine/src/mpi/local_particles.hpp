#pragma once
// What one rank holds: its own particles in slots [0, owned), and during a sub-step its halo,
// copies of other ranks' particles within reach, in slots [owned, size). Structure of arrays, the
// World the stages read; `id` maps a slot to the particle's index in the scene, which orders the
// candidates (World::id) and places the particle in the output. The slots' order is whatever
// arrivals made it: nothing the run computes depends on it.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "world.hpp"

namespace particle::detail::mpi {

// A particle as it moves to a new owner or to the output: everything it carries.
struct Record {
  double x, y, ux, uy, wall_impulse;
  std::uint64_t pair_collisions, wall_collisions;
  std::uint32_t id;
};

// A particle as a halo copy: what the pair search and resolve read.
struct Copy {
  double x, y, ux, uy;
  std::uint32_t id;
};

class LocalParticles {
 public:
  std::size_t owned() const { return owned_; }
  std::size_t size() const { return id.size(); }

  void reserve(std::size_t n) {
    for_each_array([n](auto& v) { v.reserve(n); });
  }

  // Own particles are added while there is no halo.
  void add_owned(const Record& r) {
    push(r.x, r.y, r.ux, r.uy, r.id, r.wall_impulse, r.pair_collisions, r.wall_collisions);
    owned_ = size();
  }
  void add_halo(const Copy& c) { push(c.x, c.y, c.ux, c.uy, c.id, 0, 0, 0); }
  void drop_halo() { resize(owned_); }

  Record record(std::size_t slot) const {
    return {x[slot],
            y[slot],
            ux[slot],
            uy[slot],
            wall_impulse[slot],
            pair_collisions[slot],
            wall_collisions[slot],
            id[slot]};
  }
  Copy copy(std::size_t slot) const { return {x[slot], y[slot], ux[slot], uy[slot], id[slot]}; }

  // The own particles in `gone` (slots, increasing) leave and `arriving` come, with no halo:
  // arrivals take the slots of those gone, further ones go at the end, and the last own
  // particles fill the slots still empty. O(gone + arriving), not O(owned): a sub-step's
  // migrants are a thin border's, and both come and go near the slab's edges, so an arrival in
  // a departed particle's slot keeps the slots roughly in cell order.
  void replace_owned(const std::vector<std::uint32_t>& gone, const std::vector<Record>& arriving) {
    const std::size_t filled = std::min(gone.size(), arriving.size());
    for (std::size_t k = 0; k < filled; ++k) set(gone[k], arriving[k]);
    for (std::size_t k = filled; k < arriving.size(); ++k) add_owned(arriving[k]);
    // From the last empty slot down: every slot above it is full, so the last slot is full or is
    // that one.
    std::size_t end = owned_;
    for (std::size_t k = gone.size(); k-- > filled;) {
      --end;
      if (gone[k] != end) move(end, gone[k]);
    }
    resize(end);
    owned_ = end;
  }

  // The run's World over this rank's slots: a copy of it, so that every field of the model (its
  // lengths and whatever else simulate() set) is the run's, with this rank's arrays.
  World world(const World& run) {
    World w = over_arrays(run, size(), x.data(), y.data(), ux.data(), uy.data(),
                          pair_collisions.data(), wall_collisions.data(), wall_impulse.data());
    w.id = id.data();
    return w;
  }

  std::vector<double> x, y, ux, uy, wall_impulse;
  std::vector<std::uint64_t> pair_collisions, wall_collisions;
  std::vector<std::uint32_t> id;

 private:
  void push(double px, double py, double pux, double puy, std::uint32_t pid, double impulse,
            std::uint64_t pairs, std::uint64_t walls) {
    x.push_back(px);
    y.push_back(py);
    ux.push_back(pux);
    uy.push_back(puy);
    id.push_back(pid);
    wall_impulse.push_back(impulse);
    pair_collisions.push_back(pairs);
    wall_collisions.push_back(walls);
  }
  void set(std::size_t slot, const Record& r) {
    x[slot] = r.x;
    y[slot] = r.y;
    ux[slot] = r.ux;
    uy[slot] = r.uy;
    id[slot] = r.id;
    wall_impulse[slot] = r.wall_impulse;
    pair_collisions[slot] = r.pair_collisions;
    wall_collisions[slot] = r.wall_collisions;
  }
  void move(std::size_t from, std::size_t to) {
    x[to] = x[from];
    y[to] = y[from];
    ux[to] = ux[from];
    uy[to] = uy[from];
    id[to] = id[from];
    wall_impulse[to] = wall_impulse[from];
    pair_collisions[to] = pair_collisions[from];
    wall_collisions[to] = wall_collisions[from];
  }
  void resize(std::size_t n) {
    for_each_array([n](auto& v) { v.resize(n); });
  }
  template <class Each>
  void for_each_array(Each&& each) {
    each(x), each(y), each(ux), each(uy), each(id), each(wall_impulse), each(pair_collisions);
    each(wall_collisions);
  }

  std::size_t owned_ = 0;
};

}  // namespace particle::detail::mpi
