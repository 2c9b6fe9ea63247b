// The busy neighbour: a process that spins on the CPU it was given while the object lives, and is
// gone (killed and reaped) afterwards.
#include <gtest/gtest.h>
#include <sched.h>
#include <signal.h>

#include <cerrno>
#include <chrono>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>

#include "run/neighbour.hpp"

namespace psweep {
namespace {

// The state letter and the CPU it last ran on, from /proc/PID/stat (fields 3 and 39).
std::pair<char, int> state_and_cpu(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), {});
  std::istringstream rest(text.substr(text.rfind(')') + 2));
  std::string field;
  char state = '?';
  rest >> state;
  for (int k = 4; k <= 39 && rest >> field; ++k) {
  }
  return {state, std::stoi(field)};
}

TEST(BusyNeighbour, SpinsOnItsCpuAndIsGoneAfterwards) {
  const int cpu = BusyNeighbour::last_cpu();
  pid_t pid;
  {
    BusyNeighbour busy(cpu);
    pid = busy.pid();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    cpu_set_t set;
    ASSERT_EQ(sched_getaffinity(pid, sizeof set, &set), 0);
    EXPECT_EQ(CPU_COUNT(&set), 1);
    EXPECT_TRUE(CPU_ISSET(cpu, &set));
    EXPECT_EQ(state_and_cpu(pid).second, cpu);
    EXPECT_EQ(state_and_cpu(pid).first, 'R');  // runnable: spinning, not sleeping
  }
  EXPECT_EQ(kill(pid, 0), -1);  // reaped: no such process
  EXPECT_EQ(errno, ESRCH);
}

}  // namespace
}  // namespace psweep
