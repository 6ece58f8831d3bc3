// go_feap_bench: headless lock-step exploration runs (the core classes the nodelets wrap, in
// simulated time, as fast as the CPU allows) for several scenes, planner modes and seeds, with
// per-run results and the aggregate tables of the paper (Tables II–IV).
#include <pthread.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "cli_args.h"
#include "go_feap/bench/exploration_run.h"
#include "go_feap/metrics/table.h"
#include "go_feap/world/scene_files.h"

#ifndef GO_FEAP_CONFIG_DIR
#error "GO_FEAP_CONFIG_DIR must name the package's config directory"
#endif

namespace {

using namespace go_feap;

int usage(const char* why) {
  if (why) std::cerr << "go_feap_bench: " << why << "\n";
  std::cerr
      << "usage: go_feap_bench [--scene maze|powerplant|PATH.yaml[,...]] [--seed S] [--runs N]\n"
         "                     [--planner go_feap|fuel|nearest[,...]] [--max-sim-time T] [--out DIR]\n"
         "                     [--jobs J] [--perf] [--config DIR]\n"
         "Runs N explorations per scene and planner (seeds S .. S+N-1) in simulated lock-step time and\n"
         "writes DIR/<scene>/<planner>/seed<k>/{summary.json,metrics.csv,coverage.png,events.log}, DIR/table.md,\n"
         "DIR/table.json and DIR/<scene>_coverage.png; with several planners the first against each other,\n"
         "paired by seed, in table.md and DIR/comparison.json. Defaults: maze, seed 0, 1 run, go_feap,\n"
         "900 s, results/bench-<UTC time>, 1 job, config " GO_FEAP_CONFIG_DIR ".\n"
         "--max-sim-time is each run's time limit in simulated seconds (FINISHED(time_limit) there).\n"
         "--perf prints per-block timings and the speed-up over simulated time.\n"
         "SIGINT (Ctrl-C) or SIGTERM: runs in progress end where they stand (\"interrupted\") and are\n"
         "written with the tables, runs not started are skipped, exit status 130; a second one stops at once.\n";
  return 2;
}

// The comma-separated items of `s`, empty ones included ("a,,b" and "a," have one; refused by the caller).
std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::size_t begin = 0;
  for (std::size_t comma; (comma = s.find(',', begin)) != std::string::npos; begin = comma + 1)
    out.push_back(s.substr(begin, comma - begin));
  out.push_back(s.substr(begin));
  return out;
}

// A planner mode names a file config/modes/<name>.yaml and the results folders <scene>/<name>: letters,
// digits, '_' and '-' only ("./go_feap" was another name for go_feap's file, and its runs wrote into the
// same folders; "../x" reached outside).
bool plannerNameOk(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
}

std::string sceneName(const std::string& spec) {
  std::string name = std::filesystem::path(spec).stem().string();
  return name.empty() ? spec : name;
}

struct Job {
  std::string scene_spec, planner;
  std::uint64_t seed = 0;
};

struct Outcome {
  bool ok = false;
  std::string error;
  metrics::Summary summary;
  std::vector<metrics::Sample> samples;
};

double peakRssMb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;
}

}  // namespace

int main(int argc, char** argv) {
  // SIGINT and SIGTERM are taken by a thread of their own (sigtimedwait below), blocked in every other
  // thread: blocked here, before any thread exists, so that every thread inherits the mask.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  std::map<std::string, std::string> args;
  bool help = false;
  const std::string error = tools::parseArgs(argc, argv,
                                             {{"--scene", true}, {"--seed", true}, {"--runs", true}, {"--planner", true},
                                              {"--max-sim-time", true}, {"--out", true}, {"--jobs", true},
                                              {"--perf", false}, {"--config", true}},
                                             args, help);
  if (help) return usage(nullptr), 0;
  if (!error.empty()) return usage(error.c_str());
  const std::vector<std::string> scenes = split(args.count("--scene") ? args["--scene"] : "maze");
  const std::vector<std::string> planners = split(args.count("--planner") ? args["--planner"] : "go_feap");
  unsigned long long seed = 0, runs = 1, jobs = 1;
  if (args.count("--seed") && !tools::parseCount(args["--seed"], seed)) return usage("--seed must be an integer >= 0");
  // Bounded: 1e12 runs filled memory with the job list, and 1e12 jobs asked for a vector of that size.
  constexpr unsigned long long kMaxRuns = 100000, kMaxJobs = 256;
  if (args.count("--runs") && (!tools::parseCount(args["--runs"], runs) || runs == 0 || runs > kMaxRuns))
    return usage("--runs must be an integer from 1 to 100000");
  if (args.count("--jobs") && (!tools::parseCount(args["--jobs"], jobs) || jobs == 0 || jobs > kMaxJobs))
    return usage("--jobs must be an integer from 1 to 256");
  // The runs' seeds S .. S+N-1 as given: 2^64 - 1 with two runs wrapped round to 0.
  if (runs - 1 > std::numeric_limits<unsigned long long>::max() - seed)
    return usage("--seed + --runs - 1 must fit in 64 bits");
  double max_sim_time = 900.0;  // a whole number: "3abc" and "0x4" were taken as 3 and 4
  if (args.count("--max-sim-time") && !(tools::parseNumber(args["--max-sim-time"], max_sim_time) && max_sim_time > 0.0))
    return usage("--max-sim-time must be a number > 0");
  for (const std::vector<std::string>* names : {&scenes, &planners})
    if (std::find(names->begin(), names->end(), std::string()) != names->end())
      return usage(names == &scenes ? "--scene has an empty name (two commas, or one at an end)"
                                    : "--planner has an empty name (two commas, or one at an end)");
  for (const std::string& p : planners)
    if (!plannerNameOk(p))
      return usage(("--planner '" + p + "': a mode's name has letters, digits, '_' and '-' only").c_str());
  if (args.count("--out") && args["--out"].empty()) return usage("--out must name a folder");
  // Each once: a scene or planner named twice flew its runs twice, into the same folder, and the table
  // counted them twice.
  for (const std::vector<std::string>* names : {&scenes, &planners})
    for (std::size_t i = 0; i < names->size(); ++i)
      if (std::find(names->begin(), names->begin() + i, (*names)[i]) != names->begin() + i)
        return usage(("'" + (*names)[i] + "' is named twice in " + (names == &scenes ? "--scene" : "--planner")).c_str());
  const std::string config_dir = args.count("--config") ? args["--config"] : GO_FEAP_CONFIG_DIR;
  std::string out_dir = args["--out"];
  if (out_dir.empty()) {
    // A folder of this call's own: two calls started in the same second took the same name (the first
    // had written nothing yet, so the second was not even warned), and the last to end kept the tables.
    const std::time_t now = std::time(nullptr);
    std::ostringstream name;
    name << "results/bench-" << std::put_time(std::gmtime(&now), "%Y%m%dT%H%M%SZ");
    std::error_code ec;
    std::filesystem::create_directories("results", ec);
    out_dir = name.str();
    for (int k = 2; k < 1000 && !std::filesystem::create_directory(out_dir, ec) && !ec; ++k)
      out_dir = name.str() + "-" + std::to_string(k);
  }
  const bool perf = args.count("--perf") > 0;
  // The results folder first: a file in its place used to end the bench with an uncaught exception once
  // every run had been flown.
  {
    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    if (ec || !std::filesystem::is_directory(out_dir)) {
      std::cerr << "go_feap_bench: --out " << out_dir << ": cannot make it a folder"
                << (ec ? " (" + ec.message() + ")" : std::string(" (a file of that name is there)")) << "\n";
      return 1;
    }
    // Results of an earlier call stay beside this call's (its tables hold only this call's runs).
    if (!std::filesystem::is_empty(out_dir, ec))
      std::cerr << "go_feap_bench: --out " << out_dir << " already holds results: this call's runs and tables "
                << "replace theirs, the other runs' folders stay\n";
  }

  // Check every configuration and scene before the first run starts.
  std::map<std::string, bench::ExplorationConfig> configs;
  for (const std::string& p : planners) {
    auto c = bench::loadExplorationConfig(config_dir, p);
    if (!c) {
      std::cerr << "go_feap_bench: " << c.message() << "\n";
      return 1;
    }
    configs.emplace(p, *c);
  }
  std::vector<Job> queue;
  std::map<std::string, std::uint64_t> first_seed;  // per scene spec: the seed its coverage plot shows
  std::map<std::string, std::string> folder_of, name_of;  // results folder and scene name -> spec
  for (const std::string& s : scenes) {
    auto scene = world::makeScene(s, seed);
    if (!scene) {
      std::cerr << "go_feap_bench: scene '" << s << "': " << scene.message() << "\n";
      return 1;
    }
    // The tables show the name in Markdown cells: a '|' or a line break would break their rows.
    if (scene->name.find_first_of("|\r\n") != std::string::npos) {
      std::cerr << "go_feap_bench: scene '" << s << "': its name has a '|' or a line break, which table.md cannot show\n";
      return 1;
    }
    // Two scenes must not share a results folder (named by the spec's stem) nor a name (the tables group
    // runs by it): maze and another maze.yaml wrote over each other's runs.
    for (const auto& [key, owners] : {std::make_pair(sceneName(s), &folder_of), std::make_pair(scene->name, &name_of)}) {
      const auto [it, fresh] = owners->emplace(key, s);
      if (!fresh) {
        std::cerr << "go_feap_bench: scenes '" << it->second << "' and '" << s << "' share the "
                  << (owners == &folder_of ? "results folder " + out_dir + "/" + key : "scene name '" + key + "'")
                  << ": run them in separate calls\n";
        return 1;
      }
    }
    // A scene read from a file takes no seed: every run of it would be the same run (lock-step runs are
    // deterministic), and the table would show N copies as N runs. It is run once, as seed 0.
    const unsigned long long scene_runs = scene->seeded ? runs : 1;
    first_seed[s] = scene->seeded ? seed : 0;
    if (!scene->seeded && runs > 1)
      std::cerr << "go_feap_bench: scene '" << s << "' is read from a file and takes no seed: run once per planner\n";
    for (const std::string& p : planners)
      for (unsigned long long r = 0; r < scene_runs; ++r) queue.push_back({s, p, first_seed[s] + r});
  }

  std::vector<Outcome> outcomes(queue.size());
  std::atomic<std::size_t> next{0}, done{0};
  std::mutex print_mutex;
  std::vector<double> sim_time(jobs, 0.0);
  const auto wall0 = std::chrono::steady_clock::now();
  auto last_report = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  // On a terminal a line redrawn in place twice a second; elsewhere (a log file, CI) a line per run
  // ended, as carriage returns made one endless line of a log.
  const bool terminal = ::isatty(STDERR_FILENO) == 1;
  auto report = [&](const std::string& ended = "") {
    const auto now = std::chrono::steady_clock::now();
    if (!terminal) {
      if (!ended.empty()) std::cerr << "[" << done.load() << "/" << queue.size() << " runs] " << ended << "\n";
      return;
    }
    if (ended.empty() && now - last_report < std::chrono::milliseconds(500)) return;
    last_report = now;
    std::ostringstream line;
    line << "\r[" << done.load() << "/" << queue.size() << " runs]";
    for (std::size_t j = 0; j < sim_time.size(); ++j) line << " job" << j << " t=" << std::fixed << std::setprecision(0) << sim_time[j] << "s";
    line << "   ";
    std::cerr << line.str() << std::flush;
  };
  // The first SIGINT or SIGTERM ends the runs in progress where they stand (finish reason "interrupted",
  // written with the tables as usual) and skips those not started; a second one ends the process at once.
  std::atomic<bool> interrupted{false}, all_done{false};
  std::thread signal_thread([&] {
    const timespec poll{0, 200000000};
    while (!all_done) {
      const int sig = sigtimedwait(&stop_signals, nullptr, &poll);
      if (sig != SIGINT && sig != SIGTERM) continue;
      std::lock_guard<std::mutex> lock(print_mutex);
      if (interrupted) {
        std::cerr << "\ngo_feap_bench: " << strsignal(sig) << " again: stopping without results\n";
        std::_Exit(130);
      }
      interrupted = true;
      std::cerr << "\ngo_feap_bench: " << strsignal(sig)
                << ": the runs in progress end where they stand and are written; again to stop at once\n";
    }
  });
  auto worker = [&](std::size_t job_index) {
    for (std::size_t i; (i = next++) < queue.size();) {
      const Job& job = queue[i];
      Outcome& out = outcomes[i];
      if (interrupted) {
        out.error = "not run: interrupted";
        ++done;
        continue;
      }
      try {
        auto scene = world::makeScene(job.scene_spec, job.seed);
        if (!scene) throw std::runtime_error(scene.message());
        bench::ExplorationRun run(*scene, configs.at(job.planner), job.planner, max_sim_time);
        run.run([&](const bench::Progress& p) {
          std::lock_guard<std::mutex> lock(print_mutex);
          sim_time[job_index] = p.t;
          report();
        }, &interrupted);
        out.summary = run.recorder().summary();
        out.samples = run.recorder().samples();
        std::ostringstream dir;
        dir << out_dir << "/" << sceneName(job.scene_spec) << "/" << job.planner << "/seed" << job.seed;
        // events.log first, then the recorder's files with summary.json last: its presence means all are there.
        std::string events;
        for (const std::string& e : run.events()) events += e + "\n";
        std::error_code dir_ec;
        std::filesystem::create_directories(dir.str(), dir_ec);
        // One after the other: summary.json is not written when events.log could not be.
        if (const common::Status st = metrics::writeTextWhole(dir.str() + "/events.log", events); !st.ok())
          throw std::runtime_error(st.message());
        if (const common::Status st = run.recorder().writeAll(dir.str()); !st.ok()) throw std::runtime_error(st.message());
        out.ok = true;
      } catch (const std::exception& e) {
        out.error = e.what();
      }
      ++done;
      std::lock_guard<std::mutex> lock(print_mutex);
      std::ostringstream ended;
      ended << job.scene_spec << " / " << job.planner << " / seed " << job.seed << ": ";
      if (out.ok)
        ended << out.summary.finish_reason << " at " << std::fixed << std::setprecision(1) << out.summary.exploration_time_s << " s";
      else
        ended << "failed";
      report(ended.str());
    }
  };
  std::vector<std::thread> threads;
  for (std::size_t j = 0; j < jobs; ++j) threads.emplace_back(worker, j);
  for (auto& t : threads) t.join();
  all_done = true;
  signal_thread.join();
  if (terminal) std::cerr << "\n";
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();

  std::vector<metrics::Summary> summaries;
  int failures = 0;
  for (std::size_t i = 0; i < queue.size(); ++i) {
    const Outcome& o = outcomes[i];
    if (!o.ok) {
      ++failures;
      std::cerr << "go_feap_bench: " << queue[i].scene_spec << " / " << queue[i].planner << " / seed " << queue[i].seed
                << " failed: " << o.error << "\n";
      continue;
    }
    summaries.push_back(o.summary);
    const metrics::Summary& s = o.summary;
    std::cout << std::fixed << std::setprecision(1) << s.scene << " " << s.planner << " seed " << s.seed << ": "
              << s.finish_reason
              << (s.blacklisted_frontiers > 0 ? " (" + std::to_string(s.blacklisted_frontiers) + " blacklisted frontiers left)"
                                              : std::string())
              << ", " << s.exploration_time_s << " s, " << s.flight_distance_m << " m, coverage "
              << 100.0 * s.coverage << " %, collisions " << s.collisions << ", wall " << s.wall_time_s << " s ("
              << s.exploration_time_s / std::max(1e-9, s.wall_time_s) << "x real time)\n";
  }
  const auto rows = metrics::aggregate(summaries);
  std::error_code out_ec;  // made at the start; again in case it went meanwhile, without throwing
  std::filesystem::create_directories(out_dir, out_ec);
  const auto comparisons = metrics::compare(summaries);
  // Compute times depend on how many runs shared the cores (a powerplant replan: 28.0 ms alone on a
  // core, 33.5 ms two at a time on two): say so beside them.
  const std::string md = metrics::tableMarkdown(rows, comparisons) + "\nCompute times measured with " +
                         std::to_string(std::min<std::size_t>(jobs, queue.size())) + " run(s) at a time on " +
                         std::to_string(std::thread::hardware_concurrency()) + " hardware thread(s).\n";
  // Each table whole or not at all, checked; a comparison.json left from an earlier call into the same
  // folder goes when this one compares nothing.
  std::vector<common::Status> written = {metrics::writeTextWhole(out_dir + "/table.json", metrics::tableJson(rows) + "\n"),
                                         metrics::writeTextWhole(out_dir + "/table.md", md)};
  if (!comparisons.empty())
    written.push_back(metrics::writeTextWhole(out_dir + "/comparison.json", metrics::comparisonJson(comparisons) + "\n"));
  else
    std::filesystem::remove(out_dir + "/comparison.json", out_ec);
  // Side-by-side coverage curves per scene (first seed of each planner).
  for (const std::string& s : scenes) {
    std::vector<std::pair<std::string, std::vector<metrics::Sample>>> series;
    for (std::size_t i = 0; i < queue.size(); ++i)
      if (outcomes[i].ok && queue[i].scene_spec == s && queue[i].seed == first_seed[s])
        series.emplace_back(queue[i].planner, outcomes[i].samples);
    if (!series.empty())
      written.push_back(metrics::writeWhole(out_dir + "/" + sceneName(s) + "_coverage.png", [&](const std::string& path) {
        return metrics::plotCoverage(series, sceneName(s) + " (seed " + std::to_string(first_seed[s]) + ")", path);
      }));
  }
  for (const common::Status& st : written)
    if (!st.ok()) {
      ++failures;
      std::cerr << "go_feap_bench: " << st.message() << "\n";
    }
  std::cout << "\n" << md << "\nresults: " << out_dir << "\n";
  if (perf) {
    std::cout << "\nperf (mean / max ms per call, over all runs):\n";
    std::map<std::string, metrics::BlockTime> blocks;
    double sim = 0.0, run_wall = 0.0;
    for (const metrics::Summary& s : summaries) {
      for (const auto& [name, b] : s.compute) {
        blocks[name].total_ms += b.total_ms;
        blocks[name].count += b.count;
        blocks[name].max_ms = std::max(blocks[name].max_ms, b.max_ms);
      }
      sim += s.exploration_time_s;
      run_wall += s.wall_time_s;
    }
    for (const auto& [name, b] : blocks)
      std::cout << "  " << std::left << std::setw(11) << name << std::right << std::setprecision(2) << std::setw(9)
                << b.mean() << " / " << std::setw(9) << b.max_ms << "  (" << b.count << " calls)\n";
    std::cout << std::setprecision(1) << "  simulated " << sim << " s in " << run_wall << " s of run wall time: "
              << sim / std::max(1e-9, run_wall) << "x real time; total wall " << wall << " s with " << jobs
              << " job(s); peak memory " << peakRssMb() << " MB\n";
  }
  if (interrupted) return 130;
  return failures == 0 ? 0 : 1;
}
