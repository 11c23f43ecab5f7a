// The merge's trace farm (docs/distributed.md#the-merge-farmed): `tetraprobe merge --farm DIR --workers N`
// hands every step of the merge that traces probes (passes 1-2 of the probes its hole, refinement and sliver
// rounds add, each round of the path budget) and every set of reference points (the refinement's, the SH
// fit's, the final check's) to N `tetraprobe worker` processes, through files in DIR, a
// directory every process sees (a shared filesystem). The merged level is the same bytes as without a farm.
//
// Files (each written atomically: temp + rename, so a reader sees a whole file or none):
//   DIR/merge.alive, DIR/worker_I.alive   heartbeats: a counter each process rewrites every second
//   DIR/job_K.batch                       job K (K = 0, 1, ...): the scene's content hash and a TraceBatch
//                                         (probe steps) or a ReferenceBatch (reference points)
//   DIR/job_K.I.result                    worker I's items of job K (items k with k % N == I), traced
//   DIR/job_K.I.error                     worker I could not run job K: the message
//   DIR/done, DIR/failed                  the merge finished (workers exit 0) or stopped (workers exit 1)
// The merge deletes a job's files once it has joined its results. A process whose peer's heartbeat has not
// changed for `timeout` seconds (or never appeared in that time) stops with an error naming it.
// Build side; not for engines.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "tetraprobe/bake/bake.h"

namespace tetraprobe::cli {

inline constexpr double kFarmDefaultTimeout = 600.0;

// Rewrites `path` with a counter every second until destroyed.
class Heartbeat {
 public:
  explicit Heartbeat(std::string path);
  ~Heartbeat();
  Heartbeat(const Heartbeat&) = delete;
  Heartbeat& operator=(const Heartbeat&) = delete;

 private:
  std::string path_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Watches a peer's heartbeat file: alive() is false once its content has not changed for `timeout` seconds
// (counted from construction until it first appears). Clocks of other machines play no part.
class PeerWatch {
 public:
  PeerWatch(std::string path, double timeout);
  bool alive();
  double silentSeconds() const;

 private:
  std::string path_, last_;
  double timeout_;
  double lastChange_;
};

// The merge's side: a TraceFarm (BakeOptions::farm). Creates DIR (it must hold no farm files yet: a stale
// `done` would stop new workers) and beats until finish() or destruction; the destructor writes `failed`
// unless finish() ran.
class FileFarm {
 public:
  // `progress`: a progress line (or bar) per job, counting the workers that have answered.
  FileFarm(std::string dir, int workers, uint64_t sceneHash, double timeout, bool progress = false);
  ~FileFarm();
  FileFarm(const FileFarm&) = delete;
  FileFarm& operator=(const FileFarm&) = delete;

  void trace(TraceBatch& batch);  // writes the job, waits for every worker's items, joins them in place
  void traceReferences(ReferenceBatch& batch);  // the same for reference points
  void finish();                                // writes `done`

  TraceFarm function() {
    TraceFarm f;
    f.probes = [this](TraceBatch& b) { trace(b); };
    f.references = [this](ReferenceBatch& b) { traceReferences(b); };
    return f;
  }
  int jobs() const { return jobs_; }
  uint64_t items() const { return items_; }            // probe steps sent out
  uint64_t points() const { return points_; }          // reference points sent out
  double waitSeconds() const { return waitSeconds_; }  // wall time spent waiting on the workers

 private:
  // Waits for every worker's result file of `job` (or an error, or a worker gone quiet) and hands each to
  // `decode` (bytes, path, worker); then deletes the job's files.
  void collect(uint64_t job,
               const std::function<void(const std::vector<char>&, const std::string&, int)>& decode);

  std::string dir_;
  int workers_;
  uint64_t sceneHash_;
  double timeout_;
  bool progress_;
  int jobs_ = 0;
  uint64_t items_ = 0, points_ = 0;
  double waitSeconds_ = 0.0;
  bool finished_ = false;
  std::vector<PeerWatch> watch_;
  Heartbeat beat_;
};

// A worker: traces its share of every job in `dir` until the merge writes `done` (returns normally) or
// `failed`, stops beating, or a job names another scene (InputError / std::runtime_error with the reason).
// Writes the reason to the job's error file first, so the merge names it too. `threads` 0 = all cores.
// Returns the jobs it traced.
int runFarmWorker(const SceneTracer& tracer, uint64_t sceneHash, const std::string& dir, int index, int count,
                  int threads, double timeout, bool progress);

// The job and result encodings (exposed for tests): magic "TPFARMJ1" / "TPFARMR1", fields as state_io.h
// writes them, a trailing FNV-1a.
std::string encodeFarmJob(uint64_t job, uint64_t sceneHash, const TraceBatch& batch);
TraceBatch decodeFarmJob(const std::vector<char>& bytes, const std::string& path, uint64_t& job,
                         uint64_t& sceneHash);
// Worker `index` of `count`: the items k of `batch` with k % count == index.
std::string encodeFarmResult(uint64_t job, int index, int count, const TraceBatch& batch);
// Copies the items of `bytes` (worker `index` of `count`, job `job`) into `batch`; InputError when they do not
// match (another job, worker or item set).
void decodeFarmResult(const std::vector<char>& bytes, const std::string& path, uint64_t job, int index,
                      int count, TraceBatch& batch);

}  // namespace tetraprobe::cli
