// `squeeze bench table1 [--seeds N] -o DIR`: the paper's Table I reproduced. Plans every bundled
// scene with N seeds (each within 1/20 of the paper's solution time unless --time-limit says
// otherwise), replays every plan to measure the volume change along the path, and writes
// DIR/table1.md and DIR/table1.csv side by side with the paper's figures.
//
// `squeeze bench planners [--seeds N] [--time-limit S] -o DIR` (issue 19): every registered planner
// (squeeze's "rrt" and OMPL's control planners, plan::planner_names()) on the same bundled scenes
// under the same time budget; writes DIR/planners.md (solved fraction, median time, iterations,
// nodes, path duration, largest volume change) and one OMPL benchmark log per scene,
// DIR/SCENE.log, in the text format of OMPL's Benchmark::saveResultsToStream (1.5), which
// ompl_benchmark_statistics.py and Planner Arena read.
#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "commands.h"
#include "scene_options.h"
#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/common/progress.h"
#include "squeeze/fem/scene.h"
#include "squeeze/plan/evaluate.h"
#include "squeeze/plan/planner.h"
#include <unistd.h>

namespace squeeze::cli {
namespace fs = std::filesystem;

namespace {

// Rodriguez, Lien, Amato 2006, Table I (1.7 GHz notebook, 1 GB).
struct PaperRow {
  const char* name;
  const char* file;
  const char* obstacles;
  int tets;
  int iterations;
  double seconds;
  double volume_bound;  // the paper's volume change along the path (fraction)
};
constexpr PaperRow kTable1[] = {
    {"Barriers1", "barriers1.json", "deformable", 673, 500, 10 * 60 + 34, 0.03},
    {"Barriers2", "barriers2.json", "deformable", 2343, 1000, 44 * 60 + 14, 0.03},
    {"Windows", "windows.json", "deformable", 1710, 2200, 63 * 60 + 10, 0.10},
    {"Falling Objects", "falling_objects.json", "deformable", 396, 1500, 16 * 60, 0.10},
    {"Body Parts", "body_parts.json", "rigid/deformable", 300, 640, 14 * 60 + 9, 0.05},
};

struct BenchArgs {
  std::string output, scenes = SQUEEZE_SCENES_DIR, only, integrator;
  int seeds = 3;
  double time_limit = 0, fraction = 1.0 / 20;
};

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string f2(double x, const char* f = "%.2f") {
  if (!std::isfinite(x)) return "—";
  char b[64];
  std::snprintf(b, sizeof b, f, x);
  return b;
}

// OMPL 1.5's ompl::base::PlannerStatus::asString(), in enum order (the log's "status ENUM").
constexpr const char* kOmplStatus[] = {"Unknown status", "Invalid start",       "Invalid goal",   "Unrecognized goal type",
                                       "Timeout",        "Approximate solution", "Exact solution", "Crash",
                                       "Abort"};
constexpr int kOmplTimeout = 4, kOmplApproximate = 5, kOmplExact = 6;

struct PlannersArgs {
  std::string output, scenes = SQUEEZE_SCENES_DIR, only, integrator, algorithms;
  int seeds = 5;
  double time_limit = 0, fraction = 1.0 / 20;
};

std::string mmss(double s) {
  char b[32];
  std::snprintf(b, sizeof b, "%d:%02d", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  return b;
}

std::vector<const PaperRow*> bundled_rows(const std::string& scenes, const std::string& only) {
  std::vector<const PaperRow*> rows;
  for (const PaperRow& r : kTable1)
    if (only.empty() || std::string(r.file).find(only) != std::string::npos ||
        std::string(r.name).find(only) != std::string::npos) {
      if (!fs::exists(fs::path(scenes) / r.file)) throw InputError((fs::path(scenes) / r.file).string() + ": scene file does not exist");
      rows.push_back(&r);
    }
  if (rows.empty()) throw InputError("--only " + only + ": no bundled scene matches");
  return rows;
}

void write_text(const fs::path& file, const std::string& text) {
  write_atomically(file, [&](const fs::path& p) {
    std::ofstream f(p);
    f << text;
    if (!f) throw InputError(file.string() + ": write failed");
  });
}

struct PlannerRun {
  int status = 0;  // kOmplStatus index
  bool solved = false;
  double seconds = 0, memory_mib = 0, distance = 0, duration = 0, volume = 0;
  int iterations = 0, nodes = 0;
  bool replay_matches = false;
};

int run_planners_bench(const PlannersArgs& a, bool quiet) {
  const fs::path out = a.output;
  check_output_folder(out);
  std::vector<std::string> algorithms;
  if (a.algorithms.empty()) {
    algorithms = plan::planner_names();
  } else {
    std::stringstream ss(a.algorithms);
    for (std::string name; std::getline(ss, name, ',');) {
      try {
        plan::make_planner(name);
      } catch (const InputError& e) {
        throw InputError(std::string("--algorithms: ") + e.what());
      }
      algorithms.push_back(name);
    }
  }
  const std::vector<const PaperRow*> rows = bundled_rows(a.scenes, a.only);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw InputError(a.output + ": cannot create the directory: " + ec.message());
  char host[256] = "UNKNOWN";
  gethostname(host, sizeof host - 1);

  std::ostringstream md;
  md << "| Scene | Planner | Solved | Median time (s) | Iterations (median) | Nodes (median) | Path duration (s, median) | "
        "Max volume change | Replays |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const PaperRow* r : rows) {
    const fs::path file = fs::path(a.scenes) / r->file;
    const fem::Scene scene = load_scene_with(file.string(), a.integrator);
    Progress progress(!quiet);
    fem::SceneWorld w = fem::build_scene(scene, &progress);
    const double limit = a.time_limit > 0 ? a.time_limit : r->seconds * a.fraction;
    const auto started = std::chrono::system_clock::now();
    const auto t0 = std::chrono::steady_clock::now();
    std::ostringstream planners_log;
    for (const std::string& algorithm : algorithms) {
      plan::PlannerOptions o = plan::planner_options(w);
      o.algorithm = algorithm;
      o.time_limit = limit;
      o.iterations = 100000000;  // the time limit decides
      std::vector<PlannerRun> runs;
      for (int seed = 1; seed <= a.seeds; ++seed) {
        o.seed = static_cast<std::uint64_t>(seed);
        if (!quiet) std::fprintf(stderr, "squeeze: %s, %s, seed %d of %d (limit %.0f s)\n", r->name, algorithm.c_str(), seed, a.seeds, limit);
        const plan::PlanEvaluation e = plan::evaluate_plan(w, o, &progress);
        const plan::PlanStatistics& s = e.result.stats;
        PlannerRun run;
        run.solved = e.result.status == plan::PlanStatus::solved;
        run.status = run.solved ? kOmplExact
                     : e.result.status == plan::PlanStatus::approximate ? kOmplApproximate
                                                                         : kOmplTimeout;
        run.seconds = s.seconds;
        run.memory_mib = s.peak_memory / 1048576.0;
        run.distance = s.final_distance;
        run.iterations = s.iterations;
        run.nodes = s.nodes;
        for (const plan::PathSegment& seg : e.result.path) run.duration += seg.steps * e.result.time_step;
        for (double v : e.max_volume_change) run.volume = std::max(run.volume, v);
        run.replay_matches = e.replay_matches;
        runs.push_back(run);
        if (!quiet)
          std::fprintf(stderr, "squeeze: %s, %s, seed %d: %s, %d iterations, %d nodes, %.1f s, replay %s\n", r->name,
                       algorithm.c_str(), seed, plan::to_string(e.result.status), s.iterations, s.nodes, s.seconds,
                       e.replay_matches ? "bit-identical" : "DIFFERENT");
      }
      // The markdown row: medians over the solved runs (time, iterations, nodes, duration), the
      // volume over all runs.
      std::vector<double> secs, its, nodes, durs;
      double volume = 0;
      int solved = 0, matches = 0;
      for (const PlannerRun& run : runs) {
        volume = std::max(volume, run.volume);
        matches += run.replay_matches;
        if (!run.solved) continue;
        ++solved;
        secs.push_back(run.seconds);
        its.push_back(run.iterations);
        nodes.push_back(run.nodes);
        durs.push_back(run.duration);
      }
      md << "| " << r->name << " | " << algorithm << " | " << solved << "/" << runs.size() << " | " << f2(median(secs), "%.1f")
         << " | " << f2(median(its), "%.0f") << " | " << f2(median(nodes), "%.0f") << " | " << f2(median(durs), "%.2f")
         << " | " << f2(100 * volume) << " % | " << matches << "/" << runs.size() << " |\n";
      // OMPL's benchmark log: one planner block.
      planners_log << "control_" << algorithm << "\n0 common properties\n";
      const char* props[] = {"approximate solution BOOLEAN", "graph states INTEGER",   "iterations INTEGER",
                             "max volume change REAL",       "memory REAL",            "path duration REAL",
                             "solution difference REAL",     "solved BOOLEAN",         "status ENUM",
                             "time REAL"};
      planners_log << std::size(props) << " properties for each run\n";
      for (const char* p : props) planners_log << p << "\n";
      planners_log << runs.size() << " runs\n";
      for (const PlannerRun& run : runs) {
        planners_log << (run.status == kOmplApproximate ? 1 : 0) << "; " << run.nodes << "; " << run.iterations << "; "
                     << run.volume << "; " << run.memory_mib << "; " << run.duration << "; "
                     << std::max(0.0, run.distance) << "; " << (run.solved ? 1 : 0) << "; " << run.status << "; "
                     << run.seconds << "; \n";
      }
      planners_log << ".\n";
    }
    const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::ostringstream log;
    const std::time_t start_time = std::chrono::system_clock::to_time_t(started);
    char when[64];
    std::strftime(when, sizeof when, "%Y-%m-%d %H:%M:%S", std::gmtime(&start_time));
    // ompl_benchmark_statistics.py takes the experiment's name as the line's last word: no spaces.
    std::string experiment = r->name;
    std::replace(experiment.begin(), experiment.end(), ' ', '_');
    log << "OMPL version 1.5.2\nExperiment " << experiment << "\n1 experiment properties\nscene VARCHAR(512) = " << r->file << "\n"
        << "Running on " << host << "\nStarting at " << when << "\n<<<|\nsqueeze bench planners: " << r->name
        << " (" << file.string() << "), " << w.world.tets() << " tetrahedra\n|>>>\n<<<|\n|>>>\n"
        << 1 << " is the random seed\n"
        << limit << " seconds per run\n0 MB per run\n"
        << a.seeds << " runs per planner\n"
        << total << " seconds spent to collect the data\n1 enum type\nstatus";
    for (const char* st : kOmplStatus) log << '|' << st;
    log << "\n" << algorithms.size() << " planners\n" << planners_log.str();
    std::string stem = fs::path(r->file).stem().string();
    write_text(out / (stem + ".log"), log.str());
  }
  std::ostringstream doc;
  doc << "# Planners side by side\n\n`squeeze bench planners --seeds " << a.seeds
      << (a.time_limit > 0 ? " --time-limit " + f2(a.time_limit, "%g") : std::string()) << "`: every plan within "
      << (a.time_limit > 0 ? f2(a.time_limit, "%g") + " s" : std::string("1/20 of the paper's time"))
      << "; times are wall-clock seconds of planning, medians over the solved seeds; iterations: squeeze's "
         "expansions, OMPL's controls drawn; volume: the largest |V/V0 − 1| of any object over every step of the "
         "replayed paths (settling included), over all seeds; replays: plans whose replay ends in the planner's "
         "state bit for bit.\n\n"
      << md.str();
  write_text(out / "planners.md", doc.str());
  if (!quiet) std::fprintf(stderr, "%s", doc.str().c_str());
  return kExitOk;
}

}  // namespace

Runner add_bench_command(CLI::App& app, const Global& global) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* bench = app.add_subcommand("bench", "Benchmarks of the whole planner (see also bench/ for the micro-benchmarks)");
  bench->require_subcommand(1);
  CLI::App* cmd = bench->add_subcommand(
      "table1",
      "Reproduce the paper's Table I: plan every bundled scene with N seeds, each within 1/20 of the\n"
      "paper's solution time, replay the plans, and write DIR/table1.md and DIR/table1.csv (the paper's\n"
      "columns beside squeeze's: success rate, iterations and time (median and range), iterations/s,\n"
      "peak memory, largest volume change along the replayed paths, speed-up).\n"
      "Example: squeeze bench table1 --seeds 3 -o out/table1");
  cmd->add_option("-o,--output", args->output, "Output directory (created if missing; its parent must exist)")->required();
  cmd->add_option("--seeds", args->seeds, "Seeds per scene (1..N)")->check(CLI::Range(1, 1000))->capture_default_str();
  cmd->add_option("--scenes", args->scenes, "Folder of the bundled scenes")->capture_default_str();
  cmd->add_option("--only", args->only, "Only the scene whose file or name contains this text");
  cmd->add_option("--time-limit", args->time_limit, "Seconds per plan (default: the paper's time / 20)")
      ->check(CLI::NonNegativeNumber);
  add_integrator_option(cmd, args->integrator);

  auto pargs = std::make_shared<PlannersArgs>();
  CLI::App* planners = bench->add_subcommand(
      "planners",
      "Every registered planner (squeeze's \"rrt\" and OMPL's control planners \"ompl:RRT\", \"ompl:KPIECE1\",\n"
      "\"ompl:SST\", \"ompl:EST\", \"ompl:PDST\") on the bundled scenes with N seeds under the same time\n"
      "budget. Writes DIR/planners.md (solved fraction, median time, iterations, nodes, path duration,\n"
      "largest volume change along the replayed path) and DIR/SCENE.log in OMPL's benchmark log format\n"
      "(ompl_benchmark_statistics.py, Planner Arena).\n"
      "Example: squeeze bench planners --seeds 2 --time-limit 20 -o out/planners");
  planners->add_option("-o,--output", pargs->output, "Output directory (created if missing; its parent must exist)")->required();
  planners->add_option("--seeds", pargs->seeds, "Seeds per scene and planner (1..N)")->check(CLI::Range(1, 1000))->capture_default_str();
  planners->add_option("--scenes", pargs->scenes, "Folder of the bundled scenes")->capture_default_str();
  planners->add_option("--only", pargs->only, "Only the scene whose file or name contains this text");
  planners->add_option("--algorithms", pargs->algorithms, "Comma-separated planner names (default: every registered one)");
  planners->add_option("--time-limit", pargs->time_limit, "Seconds per plan (default: the paper's time / 20)")
      ->check(CLI::NonNegativeNumber);
  add_integrator_option(planners, pargs->integrator);

  return [args, pargs, planners, &global]() -> int {
    if (planners->parsed()) return run_planners_bench(*pargs, global.quiet);
    const BenchArgs& a = *args;
    const fs::path out = a.output;
    check_output_folder(out);
    const std::vector<const PaperRow*> rows = bundled_rows(a.scenes, a.only);

    std::ostringstream md, csv;
    csv << "environment,obstacles,paper_tets,paper_iterations,paper_seconds,tets,seeds,solved,time_limit_s,"
           "iterations_median,iterations_min,iterations_max,seconds_median,seconds_min,seconds_max,"
           "iterations_per_second,peak_memory_mib,max_volume_change_pct,paper_volume_bound_pct,speedup,integrator\n";
    md << "# Table I, reproduced\n\n"
       << "Rodriguez, Lien, Amato 2006, Table I (a 1.7 GHz notebook) beside squeeze (`squeeze bench table1 --seeds "
       << a.seeds << "`). Each plan runs within "
       << (a.time_limit > 0 ? f2(a.time_limit, "%.0f") + " s" : std::string("1/20 of the paper's time"))
       << "; times are wall-clock seconds of planning (meshing cached), medians over the solved seeds with "
          "[min–max]; volume: the largest |V/V0 − 1| of any object over every step of the replayed paths "
          "(settling included); speed-up: paper time / squeeze median time.\n\n"
       << "| Environment | Obstacles | Tets (paper / squeeze) | Sol. iterations (paper / squeeze) | Sol. time (paper / "
          "squeeze) | Solved | it/s | Peak memory | Max volume change (paper bound) | Speed-up | Integrator |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const PaperRow* r : rows) {
      const fs::path file = fs::path(a.scenes) / r->file;
      const fem::Scene scene = load_scene_with(file.string(), a.integrator);
      Progress progress(!global.quiet);
      fem::SceneWorld w = fem::build_scene(scene, &progress);
      plan::PlannerOptions o = plan::planner_options(w);
      const double limit = a.time_limit > 0 ? a.time_limit : r->seconds * a.fraction;
      o.time_limit = limit;
      o.iterations = 100000000;  // the time limit decides
      std::vector<double> it, secs, all_secs;
      double rate_it = 0, rate_s = 0, peak = 0, volume = 0;
      int solved = 0;
      for (int seed = 1; seed <= a.seeds; ++seed) {
        o.seed = static_cast<std::uint64_t>(seed);
        if (!global.quiet) std::fprintf(stderr, "squeeze: %s, seed %d of %d (limit %.0f s)\n", r->name, seed, a.seeds, limit);
        const plan::PlanEvaluation e = plan::evaluate_plan(w, o, &progress);
        const plan::PlanStatistics& s = e.result.stats;
        rate_it += s.iterations;
        rate_s += s.seconds;
        peak = std::max(peak, s.peak_memory / 1048576.0);
        const bool ok = e.result.status == plan::PlanStatus::solved;
        for (double v : e.max_volume_change) volume = std::max(volume, v);
        if (ok) {
          ++solved;
          it.push_back(s.iterations);
          secs.push_back(s.seconds);
        }
        if (!global.quiet)
          std::fprintf(stderr, "squeeze: %s, seed %d: %s, %d iterations, %.1f s, %.1f it/s, replay %s\n", r->name, seed,
                       plan::to_string(e.result.status), s.iterations, s.seconds, s.iterations / s.seconds,
                       e.replay_matches ? "bit-identical" : "DIFFERENT");
      }
      const int tets = w.world.tets();
      const double mi = median(it), ms = median(secs);
      const auto lo = [](const std::vector<double>& v) { return v.empty() ? NAN : *std::min_element(v.begin(), v.end()); };
      const auto hi = [](const std::vector<double>& v) { return v.empty() ? NAN : *std::max_element(v.begin(), v.end()); };
      csv << r->name << ',' << r->obstacles << ',' << r->tets << ',' << r->iterations << ',' << r->seconds << ',' << tets
          << ',' << a.seeds << ',' << solved << ',' << limit << ',' << f2(mi, "%.0f") << ',' << f2(lo(it), "%.0f") << ','
          << f2(hi(it), "%.0f") << ',' << f2(ms) << ',' << f2(lo(secs)) << ',' << f2(hi(secs)) << ','
          << f2(rate_it / rate_s, "%.1f") << ',' << f2(peak, "%.0f") << ',' << f2(100 * volume) << ','
          << f2(100 * r->volume_bound, "%.0f") << ',' << f2(r->seconds / ms, "%.0f") << ',' << scene.integrator << '\n';
      md << "| " << r->name << " | " << r->obstacles << " | " << r->tets << " / " << tets << " | " << r->iterations
         << " / " << f2(mi, "%.0f") << " [" << f2(lo(it), "%.0f") << "–" << f2(hi(it), "%.0f") << "] | "
         << mmss(r->seconds) << " / " << f2(ms, "%.1f") << " s [" << f2(lo(secs), "%.1f") << "–" << f2(hi(secs), "%.1f")
         << "] | " << solved << "/" << a.seeds << " | " << f2(rate_it / rate_s, "%.1f") << " | " << f2(peak, "%.0f")
         << " MiB | " << f2(100 * volume) << " % (" << f2(100 * r->volume_bound, "%.0f") << " %) | "
         << f2(r->seconds / ms, "%.0f") << "× | " << scene.integrator << " |\n";
    }
    // Both tables into a staging folder beside OUT, swapped in whole (common/atomic_file.h): a kill
    // never leaves a new table1.csv beside an old table1.md.
    FolderReplacement staged(out);
    for (const auto& [name, text] : {std::pair<const char*, std::string>{"table1.csv", csv.str()}, {"table1.md", md.str()}}) {
      std::ofstream f(staged.staging() / name);
      f << text;
      if (!f) throw InputError((out / name).string() + ": write failed");
    }
    staged.commit();
    if (!global.quiet) std::fprintf(stderr, "%s", md.str().c_str());
    return kExitOk;
  };
}

}  // namespace squeeze::cli
