// The CSV writer: quoting, the column contract, rows, the reader used by --resume, atomic writes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "declaration_fixture.hpp"
#include "results/csv.hpp"

using namespace psweep;

namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

using fixture::declared;

RunSpec brute_run() {
  RunSpec run;
  run.params.engine = "brute";
  run.params.N = 1000;
  run.params.L = 20000;
  run.params.r = 1;
  run.params.S = 100;
  run.params.slow_factor = 1;
  run.params.T = 4;
  run.params.seed = 3210;
  run.pin = Pin::close;
  run.id = "0123456789ab";
  return run;
}

}  // namespace

TEST(Csv, EscapeQuotesOnlyWhenNeeded) {
  EXPECT_EQ(csv_escape("plain"), "plain");
  EXPECT_EQ(csv_escape(""), "");
  EXPECT_EQ(csv_escape("a,b"), "\"a,b\"");
  EXPECT_EQ(csv_escape("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(csv_escape("two\nlines"), "\"two\nlines\"");
  EXPECT_EQ(csv_escape("cr\r"), "\"cr\r\"");
  EXPECT_EQ(csv_escape(" lead"), "\" lead\"");
  EXPECT_EQ(csv_line({"a", "b,c", ""}), "a,\"b,c\",\n");
}

TEST(Csv, ParseRoundTripsWhatItWrites) {
  std::vector<std::vector<std::string>> rows = {{"x", "a,b", "q\"q", "", "multi\nline"},
                                                {"1", "2", "3", "4", "5"}};
  std::string text;
  for (const auto& row : rows) text += csv_line(row);
  bool partial = true;
  EXPECT_EQ(parse_csv(text, &partial), rows);
  EXPECT_FALSE(partial);
  auto cut = parse_csv(text + "7,8,\"unfinished", &partial);
  EXPECT_TRUE(partial);
  EXPECT_EQ(cut, rows);
  EXPECT_EQ(parse_csv("a,b\r\n", nullptr), (std::vector<std::vector<std::string>>{{"a", "b"}}));
}

TEST(Csv, ColumnContract) {
  // The analysis codes against these exact names and order (issue 3).
  const std::string runs =
      "config_id,engine,N,L,r,S,slow_factor,T,P,G,seed,speed_min,speed_max,scene_file,pin,"
      "neighbour,wall_stop,overlap,rep,"
      "status,"
      "exit_code,wall_s,"
      "process_s,user_s,sys_s,max_rss_kb,voluntary_switches,involuntary_switches,context_switches,"
      "cpu_migrations,"
      "page_faults,task_clock_s,cycles,instructions,branches,branch_misses,cache_misses,counters_"
      "source,simulated_instructions,simulated_cache_misses,simulated_branch_misses,broad_"
      "phase_s,"
      "narrow_phase_s,order_s,filter_s,resolve_s,advance_s,pair_tests,candidates,"
      "pair_candidates,broad_phase_builds,pair_collisions,wall_collisions,"
      "dropped,overlaps,receding_overlaps,wall_stops,energy_initial,energy_final,max_overlap,energy_drift,wall_impulse,transfer_"
      "s,"
      "interrupted,time_reached,ranks,nodes,halo_particles_max,halo_particles_mean,bytes_sent_max,"
      "bytes_sent_mean,filter_rounds,comm_s_max,comm_s_mean,wait_s_max,wait_s_mean,"
      "state_hash,engine_ran,node,"
      "cpus,oversubscribed,busy_tasks,check,check_first_step,check_detail,"
      "error\n";
  EXPECT_EQ(csv_line(runs_columns(declared())), runs);
  EXPECT_EQ(
      csv_line(summary_columns()),
      "config_id,engine,N,L,r,S,slow_factor,T,P,G,seed,speed_min,speed_max,scene_file,pin,"
      "neighbour,wall_stop,overlap,reps,"
      "failed,"
      "wall_s_min,wall_s_median,wall_s_max,builds_per_substep,state_gb_per_s\n");
}

TEST(Csv, RunsRowCellsLineUpWithColumns) {
  RunSpec run = brute_run();
  Record r;
  r.run = &run;
  r.rep = 2;
  r.status = Status::ok;
  r.exit_code = 0;
  r.process_s = 0.25;
  r.max_rss_kb = 5120;
  r.events.context_switches = 17;
  r.events.task_clock_s = 0.5;
  Metrics m;
  m.engine = "brute";
  m.wall_s = 0.125;
  m.values["broad_phase_s"] = "0.1";
  m.values["pair_tests"] = "499500";
  m.state_hash = "00ff00ff00ff00ff";
  m.cpus = {1, 0, 1, 0};
  r.metrics = m;
  r.oversubscribed = true;
  r.node = "n2";
  r.error = "x, \"y\"";
  auto row = runs_row(r, declared());
  const auto columns = runs_columns(declared());
  ASSERT_EQ(row.size(), columns.size());
  auto at = [&](const std::string& col) {
    auto i = std::find(columns.begin(), columns.end(), col) - columns.begin();
    return row[static_cast<std::size_t>(i)];
  };
  EXPECT_EQ(at("config_id"), "0123456789ab");
  EXPECT_EQ(at("N"), "1000");
  EXPECT_EQ(at("L"), "20000");
  EXPECT_EQ(at("G"), "");
  EXPECT_EQ(at("speed_min"), "");
  EXPECT_EQ(at("pin"), "close");
  EXPECT_EQ(at("rep"), "2");
  EXPECT_EQ(at("status"), "ok");
  EXPECT_EQ(at("exit_code"), "0");
  EXPECT_EQ(at("wall_s"), "0.125");
  EXPECT_EQ(at("process_s"), "0.25");
  EXPECT_EQ(at("max_rss_kb"), "5120");
  EXPECT_EQ(at("context_switches"), "17");
  EXPECT_EQ(at("cpu_migrations"), "");
  EXPECT_EQ(at("cycles"), "");
  EXPECT_EQ(at("task_clock_s"), "0.5");
  EXPECT_EQ(at("broad_phase_s"), "0.1");
  EXPECT_EQ(at("narrow_phase_s"), "");
  EXPECT_EQ(at("pair_tests"), "499500");
  EXPECT_EQ(at("state_hash"), "00ff00ff00ff00ff");
  EXPECT_EQ(at("engine_ran"), "brute");
  EXPECT_EQ(at("node"), "n2");
  EXPECT_EQ(at("cpus"), "0;1");
  EXPECT_EQ(at("oversubscribed"), "1");
  EXPECT_EQ(csv_escape(at("error")), "\"x, \"\"y\"\"\"");
  // a row survives the writer and the reader unchanged
  EXPECT_EQ(parse_csv(csv_line(row))[0], row);
}

TEST(Csv, SummaryRow) {
  RunSpec run = brute_run();
  Summary s{3, 1, 0.5, 0.75, 1.0};
  auto row = summary_row(run, s);
  ASSERT_EQ(row.size(), summary_columns().size());
  EXPECT_EQ(row[8], "");  // P: brute runs in one process
  EXPECT_EQ(row[15], "none");
  EXPECT_EQ(row[16], "per-coordinate");
  EXPECT_EQ(row[17], "approaching");
  EXPECT_EQ(row[18], "3");
  EXPECT_EQ(row[19], "1");
  EXPECT_EQ(row[20], "0.5");
  EXPECT_EQ(row[21], "0.75");
  EXPECT_EQ(row[22], "1");
  auto empty = summary_row(run, Summary{});
  EXPECT_EQ(empty[20], "");
}

TEST(Csv, AppenderWritesHeaderOnceAndAtomicWriteReplaces) {
  const std::string dir = ::testing::TempDir() + "psweep_csv_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/runs.csv";
  {
    RowAppender a(path, runs_columns(declared()));
    a.append({"1"});
  }
  {
    RowAppender a(path, runs_columns(declared()));  // reopened (resume): no second header
    a.append({"2"});
  }
  EXPECT_EQ(slurp(path), csv_line(runs_columns(declared())) + "1\n2\n");
  write_file_atomically(dir + "/s.csv", "old\n");
  write_file_atomically(dir + "/s.csv", "new\n");
  EXPECT_EQ(slurp(dir + "/s.csv"), "new\n");
  EXPECT_FALSE(std::filesystem::exists(dir + "/s.csv.tmp"));
  std::filesystem::remove_all(dir);
}

// A metric psim declares becomes a runs.csv column with no change here: after the other metrics,
// before the run's identity, read from its section with its type.
TEST(Csv, DeclaredMetricBecomesAColumn) {
  Json json = Json::parse(particle::describe_json());
  json["metrics"].push_back({{"key", "dummy_count"},
                             {"kind", "counter"},
                             {"section", "counters"},
                             {"type", "count"},
                             {"unit", "1"},
                             {"about", "test"}});
  json["metrics"].push_back({{"key", "stopped"},
                             {"kind", "status"},
                             {"section", ""},
                             {"type", "flag"},
                             {"unit", "1"},
                             {"about", "test"}});
  const Declaration d = parse_declaration(json.dump());
  const auto columns = runs_columns(d);
  const auto at = [&](const std::string& name) {
    return std::find(columns.begin(), columns.end(), name) - columns.begin();
  };
  EXPECT_EQ(at("dummy_count"), at(std::string(particle::metrics().back().key)) + 1);
  EXPECT_EQ(at("stopped"), at("dummy_count") + 1);
  EXPECT_EQ(at("state_hash"), at("stopped") + 1);

  RunSpec run = brute_run();
  Record r;
  r.run = &run;
  r.metrics = parse_metrics(
      R"({"wall_s": 1, "counters": {"pair_tests": 3, "dummy_count": 42}, "stopped": true})", d);
  const auto row = runs_row(r, d);
  ASSERT_EQ(row.size(), columns.size());
  EXPECT_EQ(row[static_cast<std::size_t>(at("dummy_count"))], "42");
  EXPECT_EQ(row[static_cast<std::size_t>(at("stopped"))], "1");
  EXPECT_EQ(row[static_cast<std::size_t>(at("pair_tests"))], "3");
  EXPECT_EQ(row[static_cast<std::size_t>(at("energy_final"))], "");
  EXPECT_THROW(parse_metrics(R"({"stopped": 1})", d), std::runtime_error);
  EXPECT_THROW(parse_metrics(R"({"counters": {"dummy_count": 1.5}})", d), std::runtime_error);
}

TEST(Declaration, RejectsWhatPsweepCannotFollow) {
  Json json = Json::parse(particle::describe_json());
  EXPECT_NO_THROW(parse_declaration(json.dump()));
  Json bad_param = json;
  bad_param["params"].push_back({{"key", "N"}, {"option", "--n"}, {"about", ""}});
  EXPECT_THROW(parse_declaration(bad_param.dump()), std::runtime_error);  // N is never left out
  Json bad_use = json;
  bad_use["engines"][0]["uses"].push_back("Q");
  EXPECT_THROW(parse_declaration(bad_use.dump()), std::runtime_error);
  Json bad_type = json;
  bad_type["metrics"][0]["type"] = "complex";
  EXPECT_THROW(parse_declaration(bad_type.dump()), std::runtime_error);
  EXPECT_THROW(parse_declaration("not json"), std::runtime_error);
}
