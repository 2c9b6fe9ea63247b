// A batch's draws sorted by cell with the disks kept from the last batch (scene/draw_batch.hpp), in
// place. The draws are counted by row and bucketed by row (their rows made again from their places
// in the stream, where keeping them would be 16 more bytes a draw), then each row is sorted by cell
// on its own: its draws' positions made once more, a counting sort over its g cells, in L1.
// O(N + g^2), g^2 about 4N; the rows split over the team.
//
// The kept disks move in two passes before the rows are sorted: to the front (each accepted disk
// to a place at or before its own: in order), then each row's to its new start (at or past its
// own: rows from the last), so that the rows are sorted within their own ranges, on any thread.
#include <algorithm>
#include <utility>

#include "scene/draw_batch.hpp"
#include "scene/pieces.hpp"

namespace particle::detail {
namespace {

// Draws a piece of the row count, at least: a piece's counts are g numbers.
constexpr std::size_t kPieceDraws = std::size_t{1} << 14;

}  // namespace

DrawBatch::DrawBatch(const DiskCells& cells, std::size_t capacity)
    : cells_(cells),
      g_(static_cast<std::size_t>(cells.side())),
      row_starts_(g_ + 1, 0),
      signposts_(g_ * signposts_a_row()),
      x_(capacity),
      y_(capacity),
      order_(capacity),
      column_(capacity),
      decisions_(capacity + kPadding) {
  assert(g_ <= 65536);  // at most 20,000 for the 10^8 disks a scene may hold
}

// The new draws' rows, where the rows go and where their kept disks are.
struct DrawBatch::Rows {
  const Draws& draws;
  std::uint64_t first;
  const std::uint32_t* draw;       // the batch's draws (places in it), row by row
  const std::uint32_t* draw_rows;  // row cy's: [draw_rows[cy], draw_rows[cy + 1])
  const std::uint32_t* kept_rows;  // row cy's kept disks: kept_rows[cy + 1] - kept_rows[cy]
};

// A thread's buffers for sort_row.
struct DrawBatch::RowScratch {
  std::vector<std::uint32_t> disks, entries;  // each cell's kept disks and entries, then places
  std::vector<double> x, y;                   // the row's draws'
  std::vector<std::uint32_t> m, cx;
};

// to(m, row of draw first + m) for m in [from, to), in order: the rows made 256 at a time, a loop
// the compiler vectorizes (the generator is a counter).
template <class To>
void DrawBatch::rows_of(const Draws& draws, std::uint64_t first, std::size_t from, std::size_t to,
                        const To& to_row) const {
  constexpr std::size_t kRun = 256;
  std::uint32_t rows[kRun];
  for (std::size_t m = from; m < to; m += kRun) {
    const std::size_t run = std::min(kRun, to - m);
    for (std::size_t k = 0; k < run; ++k)
      rows[k] = static_cast<std::uint32_t>(cells_.cell_of(draws.y(first + m + k)));
    for (std::size_t k = 0; k < run; ++k) to_row(m + k, rows[k]);
  }
}

// The accepted entries moved to the front, in order; returns where each row's start there.
std::vector<std::uint32_t> DrawBatch::keep_accepted() {
  std::vector<std::uint32_t> kept(g_ + 1);
  double *x = x_.data(), *y = y_.data();
  std::uint16_t* column = column_.data();
  const std::uint8_t* decisions = decisions_.data();
  std::uint32_t to = 0;
  for (std::size_t cy = 0; cy < g_; ++cy) {
    kept[cy] = to;
    for (std::uint32_t q = row_starts_[cy]; q < row_starts_[cy + 1]; ++q) {
      x[to] = x[q];
      y[to] = y[q];
      column[to] = column[q];
      to += decisions[q] == kAccepted;
    }
  }
  kept[g_] = to;
  return kept;
}

void DrawBatch::sort(const Draws& draws, std::uint64_t first, std::size_t count, int threads) {
  const std::size_t g = g_;
  // The draws' rows counted over pieces of the batch, then each piece's place in each row.
  const std::size_t pieces =
      std::min({static_cast<std::size_t>(threads), count / kPieceDraws + 1, std::size_t{64}});
  std::vector<std::uint32_t> counts(pieces * g, 0);
  const auto piece_range = [&](std::size_t piece) {
    return std::pair(piece * count / pieces, (piece + 1) * count / pieces);
  };
  for_pieces(threads, pieces, [&](std::size_t piece) {
    std::uint32_t* row_count = &counts[piece * g];
    const auto [from, to] = piece_range(piece);
    rows_of(draws, first, from, to, [&](std::size_t, std::uint32_t cy) { ++row_count[cy]; });
  });
  const std::vector<std::uint32_t> kept =
      size_ > 0 ? keep_accepted() : std::vector<std::uint32_t>(g + 1, 0);
  std::vector<std::uint32_t> draw_rows(g + 1);
  std::uint32_t drawn = 0;
  for (std::size_t cy = 0; cy < g; ++cy) {
    draw_rows[cy] = drawn;
    row_starts_[cy] = kept[cy] + drawn;
    for (std::size_t piece = 0; piece < pieces; ++piece)
      drawn += std::exchange(counts[piece * g + cy], drawn);
  }
  draw_rows[g] = drawn;
  row_starts_[g] = kept[g] + drawn;
  if (kept[g] > 0)
    for (std::size_t cy = g; cy-- > 0;) {
      const auto move = [&](auto& a) {
        std::copy_backward(&a[kept[cy]], &a[kept[cy + 1]],
                           &a[row_starts_[cy]] + (kept[cy + 1] - kept[cy]));
      };
      move(x_);
      move(y_);
      move(column_);
    }

  // The bucket: in the first batch the entries' orders, each row's draws where its entries go (a
  // row takes its draws out before it writes them): 4 bytes a draw not touched, 6.8 MB at the
  // million scene.
  Uninitialized<std::uint32_t> bucket;
  std::uint32_t* draw = order_.data();
  if (kept[g] > 0) {
    bucket.resize(count);
    draw = bucket.data();
  }
  for_pieces(threads, pieces, [&](std::size_t piece) {
    std::uint32_t* next = &counts[piece * g];
    const auto [from, to] = piece_range(piece);
    rows_of(draws, first, from, to, [&](std::size_t m, std::uint32_t cy) {
      draw[next[cy]++] = static_cast<std::uint32_t>(m);
    });
  });

  const Rows rows{draws, first, draw, draw_rows.data(), kept.data()};
  const std::size_t bands = std::min(static_cast<std::size_t>(threads), g);
  for_pieces(threads, bands, [&](std::size_t band) {
    RowScratch scratch{{}, std::vector<std::uint32_t>(g), {}, {}, {}, {}};
    for (std::size_t cy = band * g / bands; cy < (band + 1) * g / bands; ++cy)
      sort_row(cy, rows, scratch);
  });
  size_ = row_starts_[g];
  decisions_[none()] = kRefused;
  decisions_[more()] = kUndecided;
}

// Row cy: its cells counted (its kept disks', at its start in cell order, and its draws'), then
// the entries in place: the disks from the last (each to a place at or past its own), then the
// draws, in draw order.
void DrawBatch::sort_row(std::size_t cy, const Rows& rows, RowScratch& scratch) {
  const std::size_t g = g_;
  std::vector<std::uint32_t>&disks = scratch.disks, &entries = scratch.entries;
  std::fill(entries.begin(), entries.end(), 0u);
  const std::uint32_t row = row_starts_[cy], kept = rows.kept_rows[cy + 1] - rows.kept_rows[cy];
  if (kept > 0) {  // never in the first batch
    disks.assign(g, 0u);
    for (std::uint32_t q = row; q < row + kept; ++q) ++disks[column_[q]];
  }
  const std::uint32_t* draw = rows.draw + rows.draw_rows[cy];
  const std::uint32_t drawn = rows.draw_rows[cy + 1] - rows.draw_rows[cy];
  scratch.x.resize(drawn);
  scratch.y.resize(drawn);
  scratch.m.assign(draw, draw + drawn);
  scratch.cx.resize(drawn);
  for (std::uint32_t j = 0; j < drawn; ++j) {  // a loop the compiler vectorizes
    scratch.x[j] = rows.draws.x(rows.first + scratch.m[j]);
    scratch.y[j] = rows.draws.y(rows.first + scratch.m[j]);
    scratch.cx[j] = static_cast<std::uint32_t>(cells_.cell_of(scratch.x[j]));
  }
  for (std::uint32_t j = 0; j < drawn; ++j) ++entries[scratch.cx[j]];
  // disks[cx] becomes one past the cell's disks, entries[cx] the cell's first draw
  std::uint32_t* signposts = &signposts_[cy * signposts_a_row()];
  std::uint32_t next = row;
  for (std::size_t k = 0; k < signposts_a_row(); ++k) {
    signposts[k] = next;
    const std::size_t cx_to = std::min(g, (k + 1) * kSignpost);
    if (kept == 0) {
      for (std::size_t cx = k * kSignpost; cx < cx_to; ++cx)
        next += std::exchange(entries[cx], next);
    } else {
      for (std::size_t cx = k * kSignpost; cx < cx_to; ++cx) {
        disks[cx] += next;
        next = disks[cx] + entries[cx];
        entries[cx] = disks[cx];
      }
    }
  }
  // The arrays held in locals: a byte's store may alias any member, which would then be loaded
  // again at every entry.
  double *x = x_.data(), *y = y_.data();
  std::uint32_t* order = order_.data();
  std::uint16_t* column = column_.data();
  std::uint8_t* decisions = decisions_.data();
  std::uint32_t *disk_at = disks.data(), *entry_at = entries.data();
  for (std::uint32_t q = row + kept; q-- > row;) {
    const std::uint32_t to = --disk_at[column[q]];
    x[to] = x[q];
    y[to] = y[q];
    column[to] = column[q];
    order[to] = 0;
    decisions[to] = kAccepted;
  }
  const double *draw_x = scratch.x.data(), *draw_y = scratch.y.data();
  const std::uint32_t *draw_m = scratch.m.data(), *draw_cx = scratch.cx.data();
  for (std::uint32_t j = 0; j < drawn; ++j) {
    const std::uint32_t to = entry_at[draw_cx[j]]++;
    x[to] = draw_x[j];
    y[to] = draw_y[j];
    column[to] = static_cast<std::uint16_t>(draw_cx[j]);
    order[to] = draw_m[j] + 1;
    decisions[to] = kUndecided;
  }
}

}  // namespace particle::detail
