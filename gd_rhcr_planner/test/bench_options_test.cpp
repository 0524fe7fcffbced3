// The benchmarks' command lines (bench/bench_options.hpp), run as the user runs them: nonsense is
// rejected before anything runs, with exit code 2 and a message naming the option. Before issue
// 22, delay_benchmark read its numbers with atoi: "--robots 12abc" ran 12 robots, "--p-delay x"
// ran without delays, and a last option without its value was ignored.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <string>
#include <vector>

namespace {

struct Outcome {
  int code = -1;
  std::string output;  // stdout and stderr
};

Outcome run(const std::string& command) {
  Outcome o;
  FILE* f = popen((command + " 2>&1").c_str(), "r");
  if (!f) return o;
  char buf[512];
  while (std::fgets(buf, sizeof buf, f)) o.output += buf;
  const int status = pclose(f);
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

const std::string kSmallMap = std::string(" --map ") + GD_RHCR_MAPS_DIR + "/warehouse_small.yaml";

struct BadOption {
  std::string args, named;  // the bad arguments and the option the message must name
};

void expect_rejected(const std::string& program, const std::string& base, const std::vector<BadOption>& cases) {
  for (const BadOption& c : cases) {
    const Outcome o = run(program + base + " " + c.args);
    EXPECT_EQ(o.code, 2) << c.args << ": " << o.output;
    EXPECT_NE(o.output.find(c.named), std::string::npos) << c.args << ": the message should name " << c.named
                                                         << ": " << o.output;
  }
}

}  // namespace

TEST(DelayBenchmarkOptions, NonsenseIsRejectedNamingTheOption) {
  expect_rejected(DELAY_BENCHMARK, kSmallMap + " --ticks 2 --planner pibt",
                  {{"--robots 12abc", "--robots"},
                   {"--robots 0", "--robots"},
                   {"--robots -3", "--robots"},
                   {"--robots 99999999999999999999", "--robots"},
                   {"--robots 100000", "--robots"},  // more robots than the map's free cells
                   {"--ticks ''", "--ticks"},
                   {"--seeds 1.5", "--seeds"},
                   {"--max-delay 3x", "--max-delay"},
                   {"--speed 11", "--speed"},
                   {"--commit-horizon 0", "--commit-horizon"},
                   {"--between 2", "--between"},
                   {"--revoke yes", "--revoke"},
                   {"--p-delay x", "--p-delay"},
                   {"--p-delay 1.5", "--p-delay"},
                   {"--p-delay nan", "--p-delay"},
                   {"--param guidance", "--param"},
                   {"--robots 6 --late 7", "--late"},
                   {"--step-ticks 0", "--step-ticks"},
                   {"--step-ticks 11", "--step-ticks"},
                   {"--turning 2", "--turning"},
                   {"--action-model diagonal", "--action-model"},
                   {"--robot 5", "--robot"},  // unknown
                   {"--robots", "--robots"}});  // no value
}

TEST(DelayBenchmarkOptions, GoodOptionsRunAndHelpListsThem) {
  const Outcome ok = run(std::string(DELAY_BENCHMARK) + kSmallMap +
                         " --robots 6 --ticks 4 --planner pibt --p-delay 0.5 --late 2 --join-tick 2 --step-ticks 3 --turning 1");
  EXPECT_EQ(ok.code, 0) << ok.output;
  EXPECT_NE(ok.output.find("mean ratio"), std::string::npos) << ok.output;
  EXPECT_NE(ok.output.find("robots turn"), std::string::npos) << ok.output;
  const Outcome help = run(std::string(DELAY_BENCHMARK) + " --help");
  EXPECT_EQ(help.code, 0) << help.output;
  for (const char* option : {"--robots", "--ticks", "--p-delay", "--max-delay", "--speed", "--seeds", "--commit-horizon",
                             "--between", "--revoke", "--late", "--join-tick", "--step-ticks", "--action-model", "--turning", "--param"})
    EXPECT_NE(help.output.find(option), std::string::npos) << option;
}

TEST(DispatchBenchmarkOptions, NonsenseIsRejectedNamingTheOption) {
  expect_rejected(DISPATCH_BENCHMARK, kSmallMap,
                  {{"--robots 3x", "--robots"},
                   {"--steps 0", "--steps"},
                   {"--seeds -1", "--seeds"},
                   {"--tick-rate fast", "--tick-rate"},
                   {"--tick-rate 0", "--tick-rate"},
                   {"--steps", "--steps"}});
}
