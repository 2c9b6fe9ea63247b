#pragma once
// What a run reports besides its final state: where the time went, and what the pipeline saw.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace particle {

// Seconds per pipeline stage, summed over sub-steps. broad_phase_s is building the broad phase's
// structure; narrow_phase_s is enumerating its pairs through the exact test plus wall candidates.
struct StageTimes {
  double broad_phase_s = 0, narrow_phase_s = 0, order_s = 0, filter_s = 0, resolve_s = 0,
         advance_s = 0;
};

struct Counters {
  std::uint64_t pair_tests = 0;       // pairs the narrow phase examined
  std::uint64_t candidates = 0;       // wall and pair candidates entering the order
  // Of them, the pairs: those that can collide within their sub-step, the pairs the scene
  // needed tested (the same in every exact discrete engine; pair_tests over it is how many
  // more a broad phase leaves in). 0 where an engine has no sub-steps (event).
  std::uint64_t pair_candidates = 0;
  std::uint64_t pair_collisions = 0;  // accepted pair candidates
  // Structures the broad phase built: one a sub-step where it builds afresh each (sweep, bands,
  // grid, gpu; mpi: each rank's), fewer where it keeps one across sub-steps (cells, and auto
  // when it runs cells); 0 where there is none (brute, event).
  std::uint64_t broad_phase_builds = 0;
  std::uint64_t wall_collisions = 0;  // accepted wall candidates (a corner counts once)
  std::uint64_t dropped = 0;          // candidates the one-per-particle filter rejected
  std::uint64_t overlaps = 0;         // pairs already overlapping at a sub-step's start
  // Where the readings (docs/model.md, "Readings") part: of the overlaps, those receding (the
  // overlap readings), and collided particles whose rest of the sub-step a wall line cut (the
  // wall-stop readings). While both stay 0, every reading gives this run's state.
  std::uint64_t receding_overlaps = 0;
  std::uint64_t wall_stops = 0;
};

// What the run did to the physics, unit mass: conservation checks and accuracy measures.
struct Physics {
  double energy_initial = 0;  // kinetic energy before the first step
  double energy_final = 0;    // kinetic energy after the last step
  double max_overlap = 0;     // deepest (s - distance)/s of a pair at a sub-step's start (event:
                              // at any prediction)
  double energy_drift = 0;    // (final - initial) / initial, exact where the energies underflow
  double wall_impulse = 0;    // sum of 2 |v_normal| over wall collisions: the walls' momentum
};

// The ranks of a run on several processes (the mpi engine): what each rank's sub-steps spent on
// messages, as the largest over ranks (the slowest rank's) and the mean. Waiting is the part of
// the communication spent in the collectives of a few bytes that open each move (the sub-step's
// agreement, each filter round's sum, the counts before a halo or an exchange): their transfer
// takes microseconds, the rest is a rank that arrived early waiting for the last one.
struct RankTraffic {
  std::uint64_t ranks = 1;
  std::uint64_t nodes = 1;  // the machines the ranks ran on (mpi/engine.cpp, node_count)
  std::uint64_t filter_rounds = 0;  // over the run; every rank runs every round
  std::uint64_t halo_particles_max = 0;  // copies of other ranks' particles received
  double halo_particles_mean = 0;
  std::uint64_t bytes_sent_max = 0;  // payload handed to MPI for other ranks
  double bytes_sent_mean = 0;
  double comm_s_max = 0, comm_s_mean = 0;  // seconds in MPI calls, waiting included
  double wait_s_max = 0, wait_s_mean = 0;  // of those, seconds waiting for the other ranks
};

// Every field here that a program may want is declared once in particle/describe.hpp's metrics().
struct RunReport {
  std::string engine;  // the engine that ran (auto reports its choice)
  int threads = 1;
  std::vector<int> cpus;  // CPU each OpenMP thread was on at the end of the run
  double wall_s = 0;      // the simulation loop only
  double transfer_s = 0;  // gpu: device set-up, upload and download, outside wall_s; else 0
  // The time of the final state, in time units: S, or where a stop request ended the run early
  // (interrupted): after a whole sub-step (a multiple of 1/K), or for event at an event's time.
  double time_reached = 0;
  bool interrupted = false;
  StageTimes stages;
  Counters counters;
  Physics physics;
  std::optional<RankTraffic> ranks;  // the mpi engine's; none for a run in one process
};

}  // namespace particle
