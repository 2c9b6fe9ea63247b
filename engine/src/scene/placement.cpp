// Random placement's rule is sequential: draw k (its position from the generator's numbers 2k and
// 2k + 1) is accepted when no draw accepted before it lies closer than s, until N are accepted,
// and a particle whose kMaxPlacementAttempts draws are all refused is an error. But a draw's
// decision depends only on the earlier accepted draws within s, and a position does not depend on
// the decisions: so the draws are made a batch ahead, sorted by cell with the disks accepted
// before them and decided out of order (scene/draw_batch.hpp), each decision the rule's, on any
// number of threads. Then the decisions are read in draw order: the first N accepted are the
// particles (their positions made again from their places in the stream) and the draws up to the
// N-th are those taken; a run of kMaxPlacementAttempts refusals before it is the error, with the
// same count as the one-at-a-time placement gave.
//
// The one-at-a-time placement missed the caches at every draw (its grid of a million disks was
// ~40 MB); a sorted batch is read in memory order. A batch holds the draws expected to place the
// particles still missing (the series below, within 0.1% of the draws the million scene takes),
// 1% more and 16: the million scene's one batch of 1.69 million draws, 1.67 million of them used.
// At most a draw a cell (the 3 x 3 cells of a decision then hold a few) and at most 2N entries
// with the disks kept: near jamming (where the series fails and the last batch's rate is taken)
// more batches. Memory: 23 bytes an entry, 1 a draw (its decision in draw order; 4 more for the
// rows' bucket in a later batch), 4 a signpost (every 16th cell).
#include "scene/placement.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>
#include <vector>

#include "scene/draw_batch.hpp"
#include "scene/pieces.hpp"

namespace particle::detail {
namespace {

// The draws expected to take `placed` disks to n: the integral of 1 / (the fraction of the
// centres' square still open to a centre), that fraction from the low-coverage series of random
// sequential adsorption of disks (the available surface function to third order) at coverage
// c = disks * pi r^2 / (L - 2r)^2:
//   1 - 4c + 6 sqrt(3)/pi c^2 + (40/(sqrt(3) pi) - 176/(3 pi^2)) c^3,
// within 0.1% of the draws the million scene takes (1.675 against 1.674 million; six seeds span
// 1.671 to 1.674). Near the jamming coverage (0.547) the series fails: it is kept above 1/64,
// as is a NaN (a box of one disk's width, L = 2r, where every centre lands on one point and the
// coverage is infinite; found by make fuzz).
double expected_draws(std::size_t placed, std::size_t n, double L, double r) {
  constexpr int kSteps = 32;
  const double pi = std::numbers::pi, root3 = std::sqrt(3.0);
  const double c2 = 6 * root3 / pi, c3 = 40 / (root3 * pi) - 176 / (3 * pi * pi);
  const double span = L - 2 * r, per_disk = pi * (r / span) * (r / span);
  const double missing = static_cast<double>(n - placed);
  double draws = 0;
  for (int i = 0; i < kSteps; ++i) {
    const double c = (static_cast<double>(placed) + (i + 0.5) / kSteps * missing) * per_disk;
    const double open = 1 - 4 * c + c2 * c * c + c3 * c * c * c;
    draws += missing / kSteps / std::max(1.0 / 64, open);  // this order takes a NaN's floor
  }
  return draws;
}

// A batch's draws: those expected to place the particles still missing, a hundredth more and 16,
// or, where the last batch ended accepting fewer draws than the series says (near jamming), as many
// as its rate there asks; at most a draw a cell (the 3 x 3 cells of a decision then hold a few).
std::size_t batch_draws(std::size_t placed, std::size_t n, double L, double r, std::size_t cells,
                        double last_rate) {
  const double missing = static_cast<double>(n - placed);
  const double expected = std::max(expected_draws(placed, n, L, r), missing / last_rate);
  const double most = static_cast<double>(std::max<std::size_t>(cells, 64));
  return static_cast<std::size_t>(std::min(std::ceil(expected * 1.01) + 16, most));
}

// Below this many draws a batch takes about 0.1 ms, no more than the team's starts and waits at
// its passes cost (the default scene's 1,000 draws decided on one thread at any T).
constexpr std::size_t kTeamDraws = 4096;

// A batch's decisions read in draw order, a block of draws at a time: each block's count and first
// and last acceptance, 64 draws a step (on the team), then in draw order, draw by draw, the block
// where the N-th acceptance or a run of kMaxPlacementAttempts refusals may happen. Such a run
// covers at least one whole step of 64 refused draws.
constexpr std::size_t kStep = 64, kBlock = std::size_t{1} << 14;

// Bit i: draw i of the 64 at `decisions` accepted. A loop the compiler vectorizes.
std::uint64_t accepted_of(const std::uint8_t* decisions) {
  std::uint64_t bits = 0;
  for (std::size_t i = 0; i < kStep; ++i) bits |= std::uint64_t{decisions[i] == kAccepted} << i;
  return bits;
}

struct Block {
  std::uint32_t accepted = 0;
  std::size_t first = 0, last = 0;  // its first acceptance, and one past its last
  bool some_step_refused = false;   // 64 draws in a row, aligned: a long run may be there
};

// Decisions [from, to), `from` a multiple of kStep; the decisions are padded to one.
Block read_block(const std::uint8_t* decisions, std::size_t from, std::size_t to) {
  Block b{0, to, from, false};
  for (std::size_t m = from; m < to; m += kStep) {
    std::uint64_t bits = accepted_of(&decisions[m]);
    if (to - m < kStep) bits &= (std::uint64_t{1} << (to - m)) - 1;
    b.accepted += static_cast<std::uint32_t>(std::popcount(bits));
    b.some_step_refused |= bits == 0;
    if (bits == 0) continue;
    b.first = std::min(b.first, m + static_cast<std::size_t>(std::countr_zero(bits)));
    b.last = m + kStep - static_cast<std::size_t>(std::countl_zero(bits));
  }
  return b;
}

// Where placement stands after a batch: `placed` particles and `refused` draws in a row since the
// last acceptance, or, where it ends in the batch (the N-th acceptance: complete, or the run),
// `end`: the batch's draws up to there. placed_before: each block's first particle.
struct Reading {
  std::size_t placed = 0;
  std::uint32_t refused = 0;
  bool ends = false, complete = false;
  std::size_t end = 0;
  std::vector<std::size_t> placed_before;
};

Reading read_decisions(const std::uint8_t* decisions, std::size_t count, std::size_t n,
                       std::size_t placed, std::uint32_t refused, int threads) {
  const auto most = static_cast<std::uint32_t>(kMaxPlacementAttempts);
  const std::size_t blocks = (count + kBlock - 1) / kBlock;
  std::vector<Block> read(blocks);
  for_pieces(threads, blocks, [&](std::size_t b) {
    read[b] = read_block(decisions, b * kBlock, std::min(count, (b + 1) * kBlock));
  });
  Reading at{placed, refused, false, false, count, {}};
  for (std::size_t b = 0; b < blocks && !at.ends; ++b) {
    at.placed_before.push_back(at.placed);
    const Block& block = read[b];
    const std::size_t from = b * kBlock, to = std::min(count, (b + 1) * kBlock);
    if (at.placed + block.accepted < n && !block.some_step_refused &&
        at.refused + (block.first - from) < most) {
      at.placed += block.accepted;
      at.refused = static_cast<std::uint32_t>(to - block.last);
      continue;
    }
    for (std::size_t m = from; m < to && !at.ends; ++m) {
      if (decisions[m] == kAccepted) {
        at.refused = 0;
        at.complete = at.ends = ++at.placed == n;
      } else {
        at.ends = ++at.refused == most;
      }
      at.end = m + 1;
    }
    if (!at.ends) at.end = count;
  }
  return at;
}

// The accepted draws of [from, to) (`from` a multiple of kStep) written from particle i on: their
// positions made again from their places in the stream, 64 at a time (a loop the compiler
// vectorizes), the refused ones' for nothing.
void write_positions(Particles& p, std::size_t i, const Draws& draws, std::uint64_t first,
                     const std::uint8_t* decisions, std::size_t from, std::size_t to) {
  double x[kStep], y[kStep];
  for (std::size_t m = from; m < to; m += kStep) {
    std::uint64_t bits = accepted_of(&decisions[m]);
    if (to - m < kStep) bits &= (std::uint64_t{1} << (to - m)) - 1;
    for (std::size_t k = 0; k < kStep; ++k) {
      x[k] = draws.x(first + m + k);
      y[k] = draws.y(first + m + k);
    }
    for (; bits != 0; bits &= bits - 1, ++i) {
      p.x[i] = x[std::countr_zero(bits)];
      p.y[i] = y[std::countr_zero(bits)];
    }
  }
}

}  // namespace

Placement place_positions(Particles& p, double L, double r, double s, std::uint64_t seed,
                          int threads) {
  const std::size_t n = p.size();
  if (n == 0) return {};
  const DiskCells cells(L, s, n, 4);
  const auto cell_count = static_cast<std::size_t>(cells.side() * cells.side());
  const Draws draws(seed, r, L);
  DrawBatch batch(cells, std::max<std::size_t>(2 * n, 64));
  std::size_t placed = 0;
  std::uint32_t refused = 0;
  double last_rate = 1;  // acceptances a draw at the end of the last batch
  std::vector<std::uint8_t> by_order;
  for (std::uint64_t first = 0, count = 0;; first += count) {
    count = std::min(batch_draws(placed, n, L, r, cell_count, last_rate), batch.room(placed));
    const int team = count >= kTeamDraws ? threads : 1;
    batch.sort(draws, first, count, team);
    by_order.resize(1 + (count + kStep - 1) / kStep * kStep);
    batch.decide(team, by_order.data());
    const std::uint8_t* decided = by_order.data() + 1;
    const Reading at = read_decisions(decided, count, n, placed, refused, team);
    if (at.ends && !at.complete) return {at.placed, 0};
    for_pieces(team, at.placed_before.size(), [&](std::size_t b) {
      write_positions(p, at.placed_before[b], draws, first, decided, b * kBlock,
                      std::min(at.end, (b + 1) * kBlock));
    });
    if (at.ends) return {n, first + at.end};
    // the rate over the batch's last kBlock draws, or (none accepted there) below one in those
    const std::size_t tail = std::min(count, kBlock);
    const auto tail_accepted = std::count(decided + count - tail, decided + count, kAccepted);
    last_rate = tail_accepted > 0 ? static_cast<double>(tail_accepted) / static_cast<double>(tail)
                                  : 0.5 / static_cast<double>(tail);
    placed = at.placed;
    refused = at.refused;
  }
}

}  // namespace particle::detail
