// psweep confined: see confined.hpp.
#include "sweep/confined.hpp"

#include <fmt/format.h>

#include <csignal>
#include <cstdio>
#include <filesystem>

#include "config/config.hpp"
#include "config/program.hpp"
#include "run/confine.hpp"
#include "run/run_user.hpp"
#include "run/tier.hpp"

namespace fs = std::filesystem;

namespace psweep {

int run_confined(const ConfinedOptions& options) {
  std::vector<std::string> argv = options.command;
  argv[0] = resolve_executable(argv[0]);
  if (auto why = cannot_execute(argv[0])) {
    std::fprintf(stderr, "psweep confined: cannot execute %s: %s\n", argv[0].c_str(),
                 why->c_str());
    return 2;
  }
  std::error_code ec;
  std::vector<std::string> hide = {fs::current_path(ec).string()};
  if (!options.stdout_path.empty())
    hide.push_back(fs::weakly_canonical(fs::absolute(options.stdout_path, ec), ec)
                       .parent_path()
                       .string());
  std::unique_ptr<Tier> tier;
  if (!options.unconfined) {
    std::string why;
    tier = strongest_tier(hide, why);
    if (!tier) {
      std::fprintf(stderr, "psweep confined: cannot confine the command: %s\n", why.c_str());
      return 2;
    }
  }
  ChildIo io;
  io.stdout_path = options.stdout_path;
  io.file_size_limit = options.stdout_bytes;
  const std::vector<std::string> env = {"LC_ALL=C"};
  ChildResult result;
  if (tier) {
    io.confined = true;
    run_as_own_user_if_root(io);
    result = tier->run(Program{}, argv, env, options.timeout_s, 1, options.stdout_bytes, io,
                       nullptr);
  } else {
    result = run_child(argv, {"PATH=/usr/local/bin:/usr/bin:/bin", "LC_ALL=C"}, options.timeout_s,
                       nullptr, io);
  }
  std::fputs(result.stderr_tail.c_str(), stderr);
  switch (result.outcome) {
    case Outcome::exited:
      return result.exit_code;
    case Outcome::signaled:
      return 128 + result.signal;
    case Outcome::timed_out:
      std::fprintf(stderr, "psweep confined: killed after its timeout of %g s\n",
                   options.timeout_s);
      return 124;
    case Outcome::interrupted:
      return 130;
    case Outcome::over_limit:
      std::fprintf(stderr, "psweep confined: %s\n", result.over.c_str());
      return 128 + SIGKILL;
  }
  return 1;
}

}  // namespace psweep
