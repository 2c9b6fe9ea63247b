// find_overlaps (particle/overlaps.hpp): each particle, in index order, against those before it.
#include "particle/overlaps.hpp"

#include <utility>

#include "disk_grid.hpp"

namespace particle {

Overlaps find_overlaps(const Scene& scene) {
  const Particles& p = scene.particles;
  detail::DiskGrid earlier(scene.L, scene.contact_distance(), p.size());
  Overlaps found;
  for (std::size_t j = 0; j < p.size(); ++j) {
    earlier.any_closer(p, p.x[j], p.y[j], [&](std::size_t i) {
      if (found.pairs++ == 0 || std::pair(i, j) < std::pair(found.first_i, found.first_j)) {
        found.first_i = i;
        found.first_j = j;
      }
      return false;  // count them all
    });
    earlier.insert(p, j);
  }
  return found;
}

}  // namespace particle
