// `lasercell job run JOB.yaml --out RESULT.json [--report R.html] [--cell-out CELL.yaml]`: runs
// a localization job (localize/job_run.hpp) and writes its result file; parts not found or not
// graspable are outcomes in the result (exit 0), bad inputs exit 2.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "core/frame_graph.hpp"
#include "core/json_io.hpp"
#include "localize/job.hpp"
#include "localize/job_report.hpp"
#include "localize/job_run.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

struct JobArgs {
  std::string job, out, report, cell_out, bind = "0.0.0.0";
  int udp_port = -1;
  triangulation::GigeSourceOptions gige;
  double timeout_s = 10.0;
  int threads = -1;
  bool quiet = false;
};

void RunJobCommand(const JobArgs& args) {
  const localize::Job job = localize::ReadJobFile(args.job);
  localize::JobRunOptions options;
  options.threads = args.threads;
  options.load_meshes = !args.report.empty();
  options.source =
      MakeLiveSource(args.udp_port, args.bind, args.gige, args.timeout_s, "--timeout-s");
  if (options.source && !args.quiet) {
    std::printf("listening on %s\n", options.source->Describe().c_str());
    std::fflush(stdout);
  }
  const localize::JobResult result = localize::RunJob(job, options);
  json::WriteFile(args.out, localize::JobResultJson(result));
  if (!args.report.empty()) {
    report::WriteHtmlReport(args.report, localize::JobReport(result));
  }
  if (!args.cell_out.empty()) {
    SaveFrameGraph(args.cell_out, localize::CellWithInstances(LoadFrameGraph(job.cell), result));
  }
  if (args.quiet) return;
  std::printf("%s\n", result.Summary().c_str());
  for (const localize::PartInstance& inst : result.parts.instances) {
    std::printf("%s_from_%s: %s  support %.2f%s%s\n", job.target_frame.c_str(), inst.frame.c_str(),
                PoseToFileNotation(inst.target_from_part).c_str(),
                inst.candidate.verification.support,
                inst.graspable ? "  graspable" : "  NOT graspable: ",
                inst.graspable ? "" : inst.not_graspable_reason.c_str());
  }
  for (const localize::PartSearch& s : result.parts.searches) {
    if (s.found < s.requested) {
      std::printf("%s: %d of %d found: %s\n", s.part.c_str(), s.found, s.requested,
                  s.message.c_str());
    }
  }
  std::printf("wrote %s%s%s%s%s\n", args.out.c_str(), args.report.empty() ? "" : ", ",
              args.report.c_str(), args.cell_out.empty() ? "" : ", ", args.cell_out.c_str());
}

}  // namespace

void AddJobCommands(CLI::App& app) {
  CLI::App* job = app.add_subcommand("job", "Localization jobs: sweep -> part and grasp poses");
  job->require_subcommand(1);
  CLI::App* run = job->add_subcommand(
      "run",
      "Run a job file (lasercell.job): triangulate its sweep into the target frame and "
      "localize its parts");
  auto args = std::make_shared<JobArgs>();
  run->add_option("job", args->job, "Job file (YAML, format lasercell.job)")->required();
  run->add_option("--out", args->out, "Result JSON (lasercell.localization_job)")->required();
  run->add_option("--report", args->report, "Also write an HTML report with a 3D view");
  run->add_option("--cell-out", args->cell_out,
                  "Also write a copy of the job's cell with the found parts as frames");
  run->add_option("--threads", args->threads, "Worker threads (0 = all cores; default: the job's)")
      ->check(CLI::NonNegativeNumber);
  run->add_option("--udp", args->udp_port,
                  "Take the sweep from this UDP port (a live sensor, or `lasercell stream "
                  "send`) instead of the job's profile file");
  run->add_option("--bind", args->bind, "Listen address for --udp")->capture_default_str();
  AddGigeOptions(run, &args->gige);
  run->add_option("--timeout-s", args->timeout_s,
                  "With --udp or --gige: give up after this long without a datagram or buffer")
      ->capture_default_str();
  run->add_flag("--quiet", args->quiet, "Print nothing on success");
  run->callback([args] { RunJobCommand(*args); });
}

}  // namespace lasercell::tools
