#include "spread.hpp"

#include "results/stats.hpp"

namespace ceilings {

Spread spread_of(const std::vector<double>& values) {
  return {psweep::minimum(values), psweep::median(values), psweep::maximum(values),
          static_cast<int>(values.size())};
}

nlohmann::json to_json(const Spread& s) {
  return {{"min", s.min}, {"median", s.median}, {"max", s.max}, {"repetitions", s.repetitions}};
}

}  // namespace ceilings
