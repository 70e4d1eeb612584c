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
#include "harness/sweeps/sweep_shard.hpp"
#include "harness/sweeps/sweep_slurm.hpp"
#include "solver/schemes/threads.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double unix_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::string host_name() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return {};
  return buf;
}

class Sweep {
 public:
  Sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& opt)
      : spec_(spec),
        runs_(runs),
        opt_(opt),
        plan_(spec, runs, opt),
        recs_(runs.size()),
        table_(plan_, recs_, !opt.shard) {
    log_ = opt_.log ? opt_.log : &std::cerr;
    exe_ = opt_.executable.empty() ? fs::read_symlink("/proc/self/exe") : opt_.executable;
    if (opt_.shard) plan_.set_scope(shard_scope(runs, *opt_.shard));
    who_ = "sweep " + spec_.name + (opt_.shard ? ", " + opt_.shard->text() : "");
  }

  SweepOutcome run() {
    const auto start = Clock::now();
    started_at_ = utc_now();
    started_unix_ = unix_now();
    fs::create_directories(opt_.out_dir);
    lock();
    // A run of an interrupted sweep that still writes its folder (it holds the folder's
    // run.lock) must end before the folder is read or written.
    for (std::size_t i = 0; i < runs_.size(); ++i)
      if (plan_.in_scope(i) && fs::exists(plan_.folder(i) / "run.lock")) {
        const RunFolderLock ended(plan_.folder(i), opt_.writer_wait, *log_, "sweep " + spec_.name);
      }

    for (std::size_t i = 0; i < runs_.size(); ++i) {
      if (!plan_.in_scope(i)) continue;
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
    out_.total = plan_.scope_size();
    write_state(false);

    const std::vector<std::size_t> queue = plan_.queue(recs_);
    if (!opt_.quiet) {
      std::size_t refs = 0, searches = 0;
      for (std::size_t i = 0; i < runs_.size(); ++i)
        if (plan_.in_scope(i)) {
          refs += runs_[i].is_reference;
          searches += runs_[i].stability;
        }
      *log_ << who_ << ": " << out_.total;
      if (opt_.shard) *log_ << " of " << runs_.size();
      *log_ << " runs";
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
      table_.write(summary_path());
    });

    for (std::size_t i = 0; i < runs_.size(); ++i) {
      if (!plan_.in_scope(i)) continue;
      const RunRecord& r = recs_[i];
      if (r.status == "ok") ++out_.ok;
      else if (r.status == "diverged") ++out_.diverged;
      else ++out_.failed;
    }
    write_state(true);
    if (!opt_.quiet) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.1f", std::chrono::duration<double>(Clock::now() - start).count());
      *log_ << who_ << ": done in " << buf << " s: " << out_.ok << " ok, " << out_.diverged << " diverged, "
            << out_.failed << " failed -> " << summary_path().string();
      if (opt_.shard) *log_ << " (the sweep's summary.csv: --merge, once every shard is done)";
      *log_ << std::endl;
    }
    for (int& fd : lock_fds_)
      if (fd >= 0) close(fd), fd = -1;
    return out_;
  }

  ~Sweep() {
    for (int fd : lock_fds_)
      if (fd >= 0) close(fd);
  }
  Sweep(const Sweep&) = delete;
  Sweep& operator=(const Sweep&) = delete;

 private:
  // One sweep at a time in a folder; shards side by side (sweep_shard.hpp), one process per shard.
  void lock() {
    const fs::path sweep_lock = opt_.out_dir / "sweep.lock";
    if (!opt_.shard) {
      lock_fds_[0] = try_lock_file(sweep_lock, true);
      if (lock_fds_[0] < 0)
        throw std::runtime_error(opt_.out_dir.string() +
                                 ": another sweep is running in this folder (a sweep, a shard of one or a merge)");
      return;
    }
    lock_fds_[0] = try_lock_file(sweep_lock, false);
    if (lock_fds_[0] < 0)
      throw std::runtime_error(opt_.out_dir.string() + ": a sweep without --shard is running in this folder");
    const fs::path dir = shard_folder(opt_.out_dir, *opt_.shard);
    fs::create_directories(dir);
    lock_fds_[1] = try_lock_file(dir / "shard.lock", true);
    if (lock_fds_[1] < 0)
      throw std::runtime_error(opt_.out_dir.string() + ": " + opt_.shard->text() +
                               " is already running in this folder (it holds shards/" + opt_.shard->name() +
                               "/shard.lock)");
  }

  fs::path summary_path() const {
    return opt_.shard ? shard_folder(opt_.out_dir, *opt_.shard) / "summary.csv" : opt_.out_dir / "summary.csv";
  }

  // sweep.json and summary.csv, or a shard's shard.json and its own summary.csv.
  void write_state(bool finished) {
    table_.write(summary_path());
    if (opt_.shard) {
      write_file_atomic(shard_folder(opt_.out_dir, *opt_.shard) / "shard.json", dump_json(shard_json(finished)));
      return;
    }
    SweepJsonHead h;
    h.out = opt_.out_dir;
    h.program = exe_;
    h.jobs = opt_.jobs;
    h.threads = opt_.threads ? Json(*opt_.threads) : Json();
    h.repeat = opt_.repeat;
    h.force = opt_.force;
    h.started_at = started_at_;
    h.finished_at = finished ? Json(utc_now()) : Json();
    h.resumed = out_.resumed;
    h.counts = finished ? counts() : Json();
    write_file_atomic(opt_.out_dir / "sweep.json", dump_json(sweep_json(plan_, recs_, table_, h)));
  }

  Json counts() const {
    Json c = Json::object();
    c["executed"] = out_.executed;
    c["ok"] = out_.ok;
    c["diverged"] = out_.diverged;
    c["failed"] = out_.failed;
    return c;
  }

  // DIR/shards/K-of-N/shard.json: the shard's manifest (docs/sweeps.md, "Sharded sweeps").
  Json shard_json(bool finished) const {
    Json j = Json::object();
    j["ricochet_version"] = RICOCHET_VERSION;
    j["sweep"] = spec_.name;
    j["sweep_file"] = spec_.file;
    j["definition"] = plan_.definition();
    j["shard"] = opt_.shard->k;
    j["shards"] = opt_.shard->n;
    j["out"] = opt_.out_dir.string();
    j["program"] = exe_.string();
    j["host"] = host_name();
    j["pid"] = static_cast<long>(getpid());
    j["jobs"] = opt_.jobs;
    j["threads"] = opt_.threads ? Json(*opt_.threads) : Json();
    j["repeat"] = opt_.repeat;
    j["force"] = opt_.force;
    j["started_at"] = started_at_;
    j["finished_at"] = finished ? Json(utc_now()) : Json();
    j["started_unix"] = started_unix_;
    j["finished_unix"] = finished ? Json(unix_now()) : Json();
    j["total_runs"] = runs_.size();
    j["shard_runs"] = plan_.scope_size();
    j["resumed_runs"] = out_.resumed;
    j["counts"] = finished ? counts() : Json();
    Json ids = Json::array();
    for (std::size_t i = 0; i < runs_.size(); ++i)
      if (plan_.in_scope(i)) ids.push_back(runs_[i].id);
    j["runs"] = ids;
    return j;
  }

  const SweepSpec& spec_;
  const std::vector<SweepRun>& runs_;
  const SweepOptions& opt_;
  SweepPlan plan_;
  std::vector<RunRecord> recs_;
  SweepTable table_;
  std::ostream* log_ = nullptr;
  fs::path exe_;
  std::string who_;  // "sweep NAME" or "sweep NAME, shard K of N", for the progress lines
  SweepOutcome out_;
  std::string started_at_;
  double started_unix_ = 0.0;
  int lock_fds_[2] = {-1, -1};  // sweep.lock; a shard's shard.lock
};

// sweep.json's `reference`: the shared reference, its check run and its floor; null without one.
Json shared_reference_json(const SweepPlan& plan, const std::vector<RunRecord>& recs, SweepTable& table) {
  const SweepReference& sr = plan.spec().reference;
  if (!sr.present) return Json();
  auto run_json = [&](const std::string& id) {
    const std::size_t i = plan.index(id);
    Json e = Json::object();
    e["id"] = id;
    e["base"] = plan.run(i).base.string();
    Json o = Json::array();
    for (const auto& a : plan.run(i).set_args()) o.push_back(a);
    e["overrides"] = o;
    e["status"] = recs[i].state == RunRecord::State::done ? Json(recs[i].status) : Json();
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
  const std::optional<ReferenceMetrics>& f = table.errors().floor();
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

}  // namespace

Json sweep_json(const SweepPlan& plan, const std::vector<RunRecord>& records, SweepTable& table, const SweepJsonHead& h) {
  const SweepSpec& spec = plan.spec();
  Json j = Json::object();
  j["ricochet_version"] = RICOCHET_VERSION;
  j["sweep"] = spec.name;
  j["description"] = spec.description;
  j["sweep_file"] = spec.file;
  j["base"] = spec.base.empty() ? Json() : Json(spec.base.string());  // null: every group has its own
  j["out"] = h.out.string();
  j["program"] = h.program.string();
  j["jobs"] = h.jobs;
  j["repeat"] = h.repeat;
  j["threads"] = h.threads;
  j["force"] = h.force;
  j["started_at"] = h.started_at;
  j["finished_at"] = h.finished_at;
  j["total_runs"] = plan.size();
  j["resumed_runs"] = h.resumed;
  j["counts"] = h.counts;
  Json list = Json::array();
  for (const SweepRun& r : plan.runs()) {
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
  j["reference"] = shared_reference_json(plan, records, table);
  j["runs"] = list;
  return j;
}

SweepOutcome run_sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& options) {
  if (options.out_dir.empty()) throw InputError("ricochet sweep: no output folder");
  if (options.jobs < 1 || options.jobs > kMaxSweepJobs)
    throw InputError("ricochet sweep: --jobs: expected an integer in [1, " + std::to_string(kMaxSweepJobs) + "]");
  if (options.repeat < 1) throw InputError("ricochet sweep: --repeat: expected an integer >= 1");
  if (options.threads && (*options.threads < 0 || *options.threads > kMaxThreads))
    throw InputError("ricochet sweep: --threads: expected an integer in [0, " + std::to_string(kMaxThreads) + "]");
  if (options.shard && (options.shard->k < 1 || options.shard->k > options.shard->n || options.shard->n > kMaxShards))
    throw InputError("ricochet sweep: --shard: expected K/N with integers 1 <= K <= N <= " + std::to_string(kMaxShards) +
                     "; got '" + std::to_string(options.shard->k) + "/" + std::to_string(options.shard->n) + "'");
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
  if (c.slurm) {
    // Everything the tasks would find wrong is found here, before anything is submitted.
    check_runs(spec, runs);
    if (!c.gates_file.empty()) read_gates(c.gates_file);
    if (const std::string problem = output_folder_problem(opt.out_dir); !problem.empty())
      throw InputError("ricochet sweep: --out " + opt.out_dir.string() + ": " + problem);
    return slurm_command(c, spec.name, runs.size(), opt.out_dir, out);
  }
  check_no_slurm_options(c);
  // A shard's table is a part of the sweep's, without its errors: the gates are the merge's.
  if (opt.shard && !c.gates_file.empty())
    throw InputError("ricochet sweep: --check checks the whole sweep's table: give it to --merge, not to a shard (--shard)");
  // A bad gate file stops the sweep before any run.
  const std::optional<GateFile> gates = c.gates_file.empty() ? std::nullopt : std::optional(read_gates(c.gates_file));
  if (c.merge) {
    const MergeOutcome m = merge_sweep(spec, runs, opt);
    if (!m.complete()) {
      if (gates) {
        // No gate report may stand for a table with runs missing.
        std::error_code ec;
        fs::remove(opt.out_dir / "gates-junit.xml", ec);
        (opt.log ? *opt.log : std::cerr) << "sweep " << spec.name << ": gates not checked: " << m.missing.size()
                                         << " run(s) missing" << std::endl;
      }
      return kExitIncomplete;
    }
  } else {
    run_sweep(spec, runs, opt);
  }
  if (!gates) return 0;
  const CsvTable table = read_csv(opt.out_dir / "summary.csv");
  return run_gates(table, *gates, opt.out_dir / "gates-junit.xml", out);
}

}  // namespace ricochet
