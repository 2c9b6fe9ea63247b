// From a child's outcome and metrics to a record: statuses, errors, fallbacks.
#include <gtest/gtest.h>

#include "declaration_fixture.hpp"
#include "run/record.hpp"

using namespace psweep;

namespace {

const char* metrics_json =
    R"({"engine": "brute", "engine_requested": "brute", "threads": 2, "cpus": [1, 0],
  "wall_s": 0.5, "stages": {"broad_phase_s": 0.1, "narrow_phase_s": 0.2, "order_s": 0.01, "filter_s": 0.02,
  "resolve_s": 0.03, "advance_s": 0.04}, "counters": {"pair_tests": 1000, "candidates": 10, "pair_collisions": 5,
  "wall_collisions": 3, "dropped": 2, "overlaps": 0}, "state_hash": "0123456789abcdef", "energy_initial": 12.5,
  "energy_final": 12.5, "N": 10, "L": 100, "r": 1, "S": 5, "slow_factor": 1, "seed": 3210})";

using fixture::declared;

RunSpec spec(int threads) {
  RunSpec run;
  run.params.engine = "brute";
  run.params.T = threads;
  run.id = "abc";
  return run;
}

ChildResult exited(int code, const std::string& err = "") {
  ChildResult c;
  c.outcome = Outcome::exited;
  c.exit_code = code;
  c.process_s = 0.6;
  c.usage.ru_nvcsw = 4;
  c.usage.ru_nivcsw = 3;
  c.usage.ru_minflt = 100;
  c.usage.ru_utime.tv_sec = 1;
  c.usage.ru_utime.tv_usec = 250000;
  c.stderr_tail = err;
  return c;
}

}  // namespace

TEST(Metrics, ParsesThePsimObject) {
  Metrics m = parse_metrics(metrics_json, declared());
  EXPECT_EQ(m.engine, "brute");
  EXPECT_DOUBLE_EQ(*m.wall_s, 0.5);
  EXPECT_EQ(m.value("narrow_phase_s"), "0.2");
  EXPECT_EQ(m.value("pair_tests"), "1000");
  EXPECT_EQ(m.value("overlaps"), "0");
  EXPECT_EQ(m.value("energy_initial"), "12.5");
  EXPECT_EQ(m.state_hash, "0123456789abcdef");
  EXPECT_EQ(m.cpus, (std::vector<int>{1, 0}));
  EXPECT_THROW(parse_metrics("{", declared()), std::runtime_error);
  EXPECT_THROW(parse_metrics("[]", declared()), std::runtime_error);
  EXPECT_THROW(parse_metrics(R"({"wall_s": "fast"})", declared()), std::runtime_error);
  EXPECT_THROW(parse_metrics(R"({"counters": {"pair_tests": -1}})", declared()),
               std::runtime_error);
}

TEST(Record, OkRunWithMetrics) {
  RunSpec run = spec(2);
  Record r = make_record(run, 3, exited(0), metrics_json, 10, 2, declared());
  EXPECT_EQ(r.status, Status::ok);
  EXPECT_EQ(r.rep, 3);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_DOUBLE_EQ(r.user_s, 1.25);
  EXPECT_FALSE(r.oversubscribed);
  EXPECT_TRUE(r.error.empty());
  // no perf counters: rusage fallbacks
  EXPECT_EQ(r.events.context_switches, 7u);
  EXPECT_EQ(r.events.page_faults, 100u);
  EXPECT_FALSE(r.events.cpu_migrations);
}

TEST(Record, PerfCountersWinOverRusage) {
  RunSpec run = spec(1);
  ChildResult c = exited(0);
  c.events.context_switches = 42;
  Record r = make_record(run, 0, c, metrics_json, 10, 2, declared());
  EXPECT_EQ(r.events.context_switches, 42u);
}

TEST(Record, OversubscribedWhenThreadsExceedCores) {
  RunSpec run = spec(3);
  EXPECT_TRUE(make_record(run, 0, exited(0), metrics_json, 10, 2, declared()).oversubscribed);
  RunSpec event;
  event.params.engine = "event";
  EXPECT_FALSE(make_record(event, 0, exited(0), metrics_json, 10, 2, declared()).oversubscribed);
}

TEST(Record, FailuresBecomeRowsWithErrors) {
  RunSpec run = spec(1);
  Record bad =
      make_record(run, 0, exited(2, "psim: line 2: L: expected a number\n"), "", 10, 2, declared());
  EXPECT_EQ(bad.status, Status::failed);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(bad.error, "psim: line 2: L: expected a number");

  Record silent = make_record(run, 0, exited(1), "", 10, 2, declared());
  EXPECT_EQ(silent.error, "exit status 1");

  Record no_metrics = make_record(run, 0, exited(0), "", 10, 2, declared());
  EXPECT_EQ(no_metrics.status, Status::failed);
  EXPECT_EQ(no_metrics.error, "metrics: psim wrote no metrics file");

  Record no_wall = make_record(run, 0, exited(0), R"({"engine": "brute"})", 10, 2, declared());
  EXPECT_EQ(no_wall.status, Status::failed);

  ChildResult crash = exited(0, "boom\n");
  crash.outcome = Outcome::signaled;
  crash.signal = 11;
  Record crashed = make_record(run, 0, crash, "", 10, 2, declared());
  EXPECT_EQ(crashed.status, Status::crashed);
  EXPECT_FALSE(crashed.exit_code);
  EXPECT_EQ(crashed.error.rfind("killed by signal 11 (", 0), 0u);
  EXPECT_NE(crashed.error.find(": boom"), std::string::npos);

  ChildResult slow = exited(0);
  slow.outcome = Outcome::timed_out;
  Record timeout = make_record(run, 0, slow, metrics_json, 1.5, 2, declared());
  EXPECT_EQ(timeout.status, Status::timeout);
  EXPECT_EQ(timeout.error, "exceeded timeout_s = 1.5");
  EXPECT_FALSE(timeout.metrics);
}

TEST(Record, ErrorTailIsOneBoundedLine) {
  EXPECT_EQ(error_tail("a\nb\tc\n\n"), "a | b c");
  std::string long_text(1000, 'x');
  long_text += "END";
  std::string tail = error_tail(long_text, 50);
  EXPECT_EQ(tail.size(), 50u);
  EXPECT_EQ(tail.substr(0, 3), "...");
  EXPECT_EQ(tail.substr(47), "END");
}
