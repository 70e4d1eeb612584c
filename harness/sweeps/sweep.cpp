#include "harness/sweeps/sweep.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <system_error>

#include "harness/outputs/atomic_file.hpp"
#include "harness/outputs/csv_reader.hpp"
#include "harness/gates/gates.hpp"
#include "harness/input/input_error.hpp"
#include "harness/outputs/run_outputs.hpp"
#include "harness/sweeps/sweep_exec.hpp"
#include "solver/schemes/threads.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

class Sweep {
 public:
  Sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& opt)
      : spec_(spec), runs_(runs), opt_(opt), plan_(spec, runs, opt), recs_(runs.size()), table_(plan_, recs_) {
    log_ = opt_.log ? opt_.log : &std::cerr;
    exe_ = opt_.executable.empty() ? fs::read_symlink("/proc/self/exe") : opt_.executable;
  }

  SweepOutcome run() {
    const auto start = Clock::now();
    started_at_ = utc_now();
    fs::create_directories(opt_.out_dir);
    lock();
    // A run of an interrupted sweep that still writes its folder (it holds the folder's
    // run.lock) must end before the folder is read or written.
    for (std::size_t i = 0; i < runs_.size(); ++i)
      if (fs::exists(plan_.folder(i) / "run.lock")) {
        const RunFolderLock ended(plan_.folder(i), opt_.writer_wait, *log_, "sweep " + spec_.name);
      }

    for (std::size_t i = 0; i < runs_.size(); ++i) {
      RunRecord& rec = recs_[i];
      std::string note;
      if (!opt_.force && plan_.load_finished(i, rec, note)) {
        rec.state = RunRecord::State::done;
        rec.resumed = true;
        ++out_.resumed;
      } else if (!note.empty()) {
        *log_ << "sweep " << spec_.name << ": " << note << "; run again" << std::endl;
      }
    }
    out_.total = runs_.size();
    write_sweep_json(false);
    table_.write(opt_.out_dir / "summary.csv");

    const std::vector<std::size_t> queue = plan_.queue(recs_);
    if (!opt_.quiet) {
      std::size_t refs = 0, searches = 0;
      for (const auto& r : runs_) {
        refs += r.is_reference;
        searches += r.stability;
      }
      *log_ << "sweep " << spec_.name << ": " << runs_.size() << " runs";
      if (refs) *log_ << " (" << refs << " reference)";
      if (searches) *log_ << " (" << searches << " stability searches)";
      *log_ << ", " << out_.resumed << " done before, " << queue.size() << " to run, "
            << (opt_.jobs == 1 ? std::string("one at a time") : std::to_string(opt_.jobs) + " in parallel");
      if (opt_.repeat > 1) *log_ << ", each " << opt_.repeat << " times (reference runs once)";
      *log_ << " -> " << opt_.out_dir.string() << std::endl;
    }

    SweepExecution(plan_, recs_, opt_, exe_, start, out_.resumed).run(queue, [&](std::size_t i) {
      ++out_.executed;
      table_.run_done(i);
      table_.write(opt_.out_dir / "summary.csv");
    });

    for (const RunRecord& r : recs_) {
      if (r.status == "ok") ++out_.ok;
      else if (r.status == "diverged") ++out_.diverged;
      else ++out_.failed;
    }
    table_.write(opt_.out_dir / "summary.csv");
    write_sweep_json(true);
    if (!opt_.quiet) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.1f", std::chrono::duration<double>(Clock::now() - start).count());
      *log_ << "sweep " << spec_.name << ": done in " << buf << " s: " << out_.ok << " ok, " << out_.diverged
            << " diverged, " << out_.failed << " failed -> " << (opt_.out_dir / "summary.csv").string() << std::endl;
    }
    if (lock_fd_ >= 0) close(lock_fd_);
    lock_fd_ = -1;
    return out_;
  }

  ~Sweep() {
    if (lock_fd_ >= 0) close(lock_fd_);
  }
  Sweep(const Sweep&) = delete;
  Sweep& operator=(const Sweep&) = delete;

 private:
  // One sweep at a time in a folder.
  void lock() {
    const fs::path p = opt_.out_dir / "sweep.lock";
    lock_fd_ = ::open(p.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (lock_fd_ < 0)
      throw std::runtime_error("cannot write '" + p.string() + "': " + std::generic_category().message(errno));
    if (flock(lock_fd_, LOCK_EX | LOCK_NB) != 0)
      throw std::runtime_error(opt_.out_dir.string() + ": another sweep is running in this folder");
  }

  // sweep.json's `reference`: the shared reference, its check run and its floor; null without one.
  Json shared_reference_json() {
    const SweepReference& sr = spec_.reference;
    if (!sr.present) return Json();
    auto run_json = [&](const std::string& id) {
      const std::size_t i = plan_.index(id);
      Json e = Json::object();
      e["id"] = id;
      e["base"] = runs_[i].base.string();
      Json o = Json::array();
      for (const auto& a : runs_[i].set_args()) o.push_back(a);
      e["overrides"] = o;
      e["status"] = recs_[i].state == RunRecord::State::done ? Json(recs_[i].status) : Json();
      return e;
    };
    Json j = run_json(sr.id());
    j["name"] = sr.name;
    j["error_probe"] = sr.error_probe;
    if (sr.check.empty()) {
      j["check"] = nullptr;
      j["floor"] = nullptr;
      return j;
    }
    j["check"] = run_json(sr.check_id());
    const std::optional<ReferenceMetrics>& f = table_.errors().floor();
    if (!f) {
      j["floor"] = nullptr;
      return j;
    }
    Json fl = Json::object();
    for (const auto& [name, value] : metric_values(*f, sr.error_probe))
      if (has_floor(name)) fl[name] = value && std::isfinite(*value) ? Json(*value) : Json();
    fl["impulse_source"] = f->impulse_source.empty() ? Json() : Json(f->impulse_source);
    j["floor"] = fl;
    return j;
  }

  void write_sweep_json(bool finished) {
    Json j = Json::object();
    j["ricochet_version"] = RICOCHET_VERSION;
    j["sweep"] = spec_.name;
    j["description"] = spec_.description;
    j["sweep_file"] = spec_.file;
    j["base"] = spec_.base.empty() ? Json() : Json(spec_.base.string());  // null: every group has its own
    j["out"] = opt_.out_dir.string();
    j["program"] = exe_.string();
    j["jobs"] = opt_.jobs;
    j["repeat"] = opt_.repeat;
    j["threads"] = opt_.threads ? Json(*opt_.threads) : Json();
    j["force"] = opt_.force;
    j["started_at"] = started_at_;
    j["finished_at"] = finished ? Json(utc_now()) : Json();
    j["total_runs"] = runs_.size();
    j["resumed_runs"] = out_.resumed;
    if (finished) {
      Json c = Json::object();
      c["executed"] = out_.executed;
      c["ok"] = out_.ok;
      c["diverged"] = out_.diverged;
      c["failed"] = out_.failed;
      j["counts"] = c;
    } else {
      j["counts"] = nullptr;
    }
    Json list = Json::array();
    for (const SweepRun& r : runs_) {
      Json e = Json::object();
      e["id"] = r.id;
      e["group"] = r.group;
      e["kind"] = r.is_reference ? "reference" : r.stability ? "stability" : "run";
      e["base"] = r.base.string();
      e["folder"] = r.folder().string();
      Json o = Json::array();
      for (const auto& a : r.set_args()) o.push_back(a);
      e["overrides"] = o;
      Json sw = Json::array();
      for (const auto& k : r.swept) sw.push_back(k);
      e["swept"] = sw;
      if (r.stability) {  // a run's entry stays as it was
        Json so = Json::array();
        for (const SweepStabilityOption& o : r.stability_options) so.push_back(o.flag + "=" + o.text);
        e["stability_options"] = so;
      }
      e["reference_run"] = r.reference_id.empty() ? Json() : Json(r.reference_id);
      e["reference_kind"] = r.reference_kind.empty() ? Json() : Json(r.reference_kind);
      list.push_back(e);
    }
    j["reference"] = shared_reference_json();
    j["runs"] = list;
    write_file_atomic(opt_.out_dir / "sweep.json", dump_json(j));
  }

  const SweepSpec& spec_;
  const std::vector<SweepRun>& runs_;
  const SweepOptions& opt_;
  SweepPlan plan_;
  std::vector<RunRecord> recs_;
  SweepTable table_;
  std::ostream* log_ = nullptr;
  fs::path exe_;
  SweepOutcome out_;
  std::string started_at_;
  int lock_fd_ = -1;
};

}  // namespace

SweepOutcome run_sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& options) {
  if (options.out_dir.empty()) throw InputError("ricochet sweep: no output folder");
  if (options.jobs < 1 || options.jobs > kMaxSweepJobs)
    throw InputError("ricochet sweep: --jobs: expected an integer in [1, " + std::to_string(kMaxSweepJobs) + "]");
  if (options.repeat < 1) throw InputError("ricochet sweep: --repeat: expected an integer >= 1");
  if (options.threads && (*options.threads < 0 || *options.threads > kMaxThreads))
    throw InputError("ricochet sweep: --threads: expected an integer in [0, " + std::to_string(kMaxThreads) + "]");
  check_runs(spec, runs);
  if (const std::string problem = output_folder_problem(options.out_dir); !problem.empty())
    throw InputError("ricochet sweep: --out " + options.out_dir.string() + ": " + problem);
  Sweep s(spec, runs, options);
  return s.run();
}

int run_command(const SweepCommand& c, std::ostream& out) {
  const SweepSpec spec = read_sweep(c.file);
  SweepOptions opt = c.options;
  if (opt.out_dir.empty()) opt.out_dir = fs::path("results") / spec.name;
  const std::vector<SweepRun> runs = expand(spec);
  // A bad gate file stops the sweep before any run.
  const std::optional<GateFile> gates = c.gates_file.empty() ? std::nullopt : std::optional(read_gates(c.gates_file));
  run_sweep(spec, runs, opt);
  if (!gates) return 0;
  const CsvTable table = read_csv(opt.out_dir / "summary.csv");
  return run_gates(table, *gates, opt.out_dir / "gates-junit.xml", out);
}

}  // namespace ricochet
