#include "results/ceilings.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "config/program.hpp"
#include "results/results.hpp"
#include "run/runner.hpp"

namespace fs = std::filesystem;

namespace psweep {
namespace {

std::string machine_key() {
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  std::ifstream in("/etc/machine-id");
  std::string id;
  std::getline(in, id);
  return std::string(host) + (id.empty() ? "" : "-" + id);
}

std::optional<Json> read_cache(const fs::path& path, const std::string& hash) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  Json cached = Json::parse(in, nullptr, false);
  if (cached.is_discarded() || !cached.is_object() || cached.value("executable_hash", "") != hash)
    return std::nullopt;
  return cached;
}

}  // namespace

Json machine_ceilings(const std::string& executable, const std::string& cache_dir) {
  const std::string hash = access(executable.c_str(), X_OK) == 0 ? file_hash(executable) : "";
  if (hash.empty()) {
    std::fprintf(stderr,
                 "psweep: %s not found: meta.json records no ceilings (make tools builds it)\n",
                 executable.c_str());
    return nullptr;
  }
  const fs::path cache = fs::path(cache_dir) / (machine_key() + ".json");
  if (auto cached = read_cache(cache, hash)) {
    (*cached)["source"] = "cached";
    return *cached;
  }
  std::fprintf(stderr, "psweep: measuring this machine's ceilings once for this build (%s)\n",
               executable.c_str());
  const auto out = capture_output({executable});
  Json ceilings = out ? Json::parse(*out, nullptr, false) : Json();
  if (!out || ceilings.is_discarded() || !ceilings.is_object()) {
    std::fprintf(stderr, "psweep: %s failed: meta.json records no ceilings\n", executable.c_str());
    return nullptr;
  }
  ceilings = cache_ceilings(std::move(ceilings), executable, cache_dir);
  ceilings["source"] = "measured";
  return ceilings;
}

Json cache_ceilings(Json ceilings, const std::string& executable, const std::string& cache_dir) {
  ceilings["executable"] = executable;
  ceilings["executable_hash"] = file_hash(executable);
  std::error_code ec;
  fs::create_directories(cache_dir, ec);
  try {
    write_json((fs::path(cache_dir) / (machine_key() + ".json")).string(), ceilings);
  } catch (const std::exception& e) {  // a read-only build folder: measured again next time
    std::fprintf(stderr, "ceilings not cached: %s\n", e.what());
  }
  return ceilings;
}

std::string ceilings_cache(const std::string& executable) {
  return (fs::path(executable).parent_path() / "ceilings-cache").string();
}

Json machine_ceilings() {
  std::string executable = "ceilings";
  std::error_code ec;
  if (const char* env = std::getenv("PSWEEP_CEILINGS"); env && *env)
    executable = env;
  else if (auto self = fs::read_symlink("/proc/self/exe", ec); !ec)
    executable = (self.parent_path() / "ceilings").string();
  return machine_ceilings(executable, ceilings_cache(executable));
}

}  // namespace psweep
