#pragma once
// A figure measured several times: its minimum, median and maximum (psweep's own statistics,
// results/stats.hpp), kept with the repetitions' count. On a shared machine the spread is the
// point: a ceiling whose maximum is twice its minimum was measured while something else ran.
#include <nlohmann/json.hpp>
#include <vector>

namespace ceilings {

struct Spread {
  double min = 0, median = 0, max = 0;
  int repetitions = 0;
};

// Precondition: `values` not empty.
Spread spread_of(const std::vector<double>& values);
nlohmann::json to_json(const Spread& s);

}  // namespace ceilings
