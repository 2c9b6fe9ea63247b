// The results folder as a place several processes may reach: one psweep (sweep or merge) at a
// time holds it, and the results of an earlier sweep are set aside, never overwritten.
#pragma once

#include <filesystem>
#include <string>

#include "results/results.hpp"

namespace psweep {

// Another psweep holds the folder: exit status 2; the message already says who and what to do.
struct FolderBusy : ResultsError {
  using ResultsError::ResultsError;
};

// flock() on FOLDER/.psweep.lock, which records the holder's PID, for as long as this lives.
// The kernel drops the lock when the holder ends in any way (kill -9 included), so a stale lock
// file is never in the way. Creates the folder when missing; throws FolderBusy when it is held.
class FolderLock {
 public:
  explicit FolderLock(const std::filesystem::path& folder);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

// Whether `out` holds results (runs.csv, summary.csv or meta.json).
bool holds_results(const std::filesystem::path& out);

// Moves the results in `out` to the first of out/previous, out/previous-2, ... not yet there,
// so every earlier sweep is kept; says where on stderr. Nothing to move: nothing happens.
void set_aside_previous(const std::filesystem::path& out);

}  // namespace psweep
