// The merge's trace farm: job and result files, heartbeats, the merge's and a worker's loops (trace_farm.h).
#include "trace_farm.h"

#include <chrono>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>

#include "args.h"
#include "state_io.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/common/progress.h"
#include "tetraprobe/runtime/file_io.h"

namespace tetraprobe::cli {

namespace {

namespace fs = std::filesystem;

constexpr char kJobMagic[8] = {'T', 'P', 'F', 'A', 'R', 'M', 'J', '1'};
constexpr char kResultMagic[8] = {'T', 'P', 'F', 'A', 'R', 'M', 'R', '1'};
constexpr char kPointJobMagic[8] = {'T', 'P', 'F', 'A', 'R', 'M', 'P', '1'};
constexpr char kPointResultMagic[8] = {'T', 'P', 'F', 'A', 'R', 'M', 'Q', '1'};
constexpr auto kPoll = std::chrono::milliseconds(20);

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void writeAtomic(const std::string& path, const std::string& bytes) {
  std::string error;
  if (!writeFileAtomic(path, bytes, &error)) throw std::runtime_error(error);
}

// The file's bytes, or nullopt when it is not there (or went between the look and the read). A file that is
// there and cannot be read is an error, not a wait: farm files are ours, of any size (no read limit).
std::optional<std::vector<char>> readIfThere(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  std::vector<char> bytes;
  std::string error;
  if (readFile(path, bytes, &error, std::numeric_limits<uint64_t>::max())) return bytes;
  if (!fs::exists(path, ec)) return std::nullopt;
  throw std::runtime_error(error);
}

std::string jobPath(const std::string& dir, uint64_t job) {
  return dir + "/job_" + std::to_string(job) + ".batch";
}
std::string resultPath(const std::string& dir, uint64_t job, int index, const char* ext) {
  return dir + "/job_" + std::to_string(job) + "." + std::to_string(index) + ext;
}

// The bake options a batch's tracing reads (the streams' seed, the sampling settings, the light content).
void putOptions(ByteWriter& w, const BakeOptions& o) {
  w.put(int32_t(o.bounces));
  w.put(int32_t(o.samplesPerProbe));
  w.put(o.targetRelError);
  w.put(int32_t(o.maxSamplesPerProbe));
  w.put(o.pathBudget);
  w.put(int32_t(o.pass2MaxSamples));
  w.put(o.litVoxel);
  w.put(uint8_t(o.guide));
  w.put(int32_t(o.litPatches));
  w.put(o.content);
  w.put(o.seed);
  w.put(int32_t(o.shOrder));
}

BakeOptions getOptions(ByteReader& r) {
  BakeOptions o;
  o.bounces = r.get<int32_t>();
  o.samplesPerProbe = r.get<int32_t>();
  o.targetRelError = r.get<double>();
  o.maxSamplesPerProbe = r.get<int32_t>();
  o.pathBudget = r.get<uint64_t>();
  o.pass2MaxSamples = r.get<int32_t>();
  o.litVoxel = r.get<double>();
  o.guide = r.get<uint8_t>() != 0;
  const int32_t lit = r.get<int32_t>();
  if (lit < 0 || lit > int32_t(LitPatches::kBounces)) r.fail("unknown lit-patch mode");
  o.litPatches = LitPatches(lit);
  o.content = r.get<uint32_t>();
  o.seed = r.get<uint64_t>();
  o.shOrder = r.get<int32_t>();
  o.progress = false;
  return o;
}

// How many of `size` items a worker takes: those k with k % count == index.
uint64_t shareOf(size_t size, int index, int count) {
  return size > size_t(index) ? uint64_t((size - size_t(index) + size_t(count) - 1) / size_t(count)) : 0;
}

// A result file's header: magic, job, worker index and count, its items.
void putResultHeader(ByteWriter& w, const char (&magic)[8], uint64_t job, int index, int count, size_t size) {
  w.bytes.assign(magic, magic + 8);
  w.put(job);
  w.put(uint32_t(index));
  w.put(uint32_t(count));
  w.put(shareOf(size, index, count));
}

void checkResultHeader(ByteReader& r, const char (&magic)[8], uint64_t job, int index, int count,
                       size_t size) {
  r.open(magic);
  if (r.get<uint64_t>() != job) r.fail("is for another job");
  if (r.get<uint32_t>() != uint32_t(index) || r.get<uint32_t>() != uint32_t(count))
    r.fail("is from another worker or farm size");
  if (r.get<uint64_t>() != shareOf(size, index, count)) r.fail("holds another number of items");
}

// Runs `run` on a copy of `batch` holding only this worker's items, then puts them back in their places.
template <class Batch, class Run>
void runShare(Batch& batch, int index, int count, Run&& run) {
  Batch mine = batch;
  mine.items.clear();
  for (size_t k = size_t(index); k < batch.items.size(); k += size_t(count))
    mine.items.push_back(batch.items[k]);
  if (!mine.items.empty()) run(mine);
  for (size_t k = size_t(index), n = 0; k < batch.items.size(); k += size_t(count), ++n)
    batch.items[k] = std::move(mine.items[n]);
}

}  // namespace

Heartbeat::Heartbeat(std::string path) : path_(std::move(path)) {
  writeAtomic(path_, "0");
  thread_ = std::thread([this] {
    uint64_t n = 0;
    while (!stop_.load()) {
      for (int k = 0; k < 50 && !stop_.load(); ++k) std::this_thread::sleep_for(kPoll);
      std::string error;
      writeFileAtomic(path_, std::to_string(++n), &error);  // a missed beat is retried next second
    }
  });
}

Heartbeat::~Heartbeat() {
  stop_.store(true);
  thread_.join();
}

PeerWatch::PeerWatch(std::string path, double timeout)
    : path_(std::move(path)), timeout_(timeout), lastChange_(now()) {}

bool PeerWatch::alive() {
  if (const auto bytes = readIfThere(path_)) {
    std::string text(bytes->begin(), bytes->end());
    if (text != last_) {
      last_ = std::move(text);
      lastChange_ = now();
    }
  }
  return silentSeconds() <= timeout_;
}

double PeerWatch::silentSeconds() const {
  return now() - lastChange_;
}

std::string encodeFarmJob(uint64_t job, uint64_t sceneHash, const TraceBatch& b) {
  ByteWriter w;
  w.bytes.assign(kJobMagic, kJobMagic + 8);
  w.put(job);
  w.put(sceneHash);
  w.put(uint32_t(b.step));
  w.put(b.floor);
  w.put(b.litVoxel);
  w.put(b.capBatches);
  putOptions(w, b.options);
  w.put(uint64_t(b.items.size()));
  for (const TraceItem& item : b.items) {
    w.put(item.index);
    w.put(item.position.x);
    w.put(item.position.y);
    w.put(item.position.z);
    w.put(item.stop);
    putProbeState(w, item.state);
  }
  w.seal();
  return std::move(w.bytes);
}

TraceBatch decodeFarmJob(const std::vector<char>& bytes, const std::string& path, uint64_t& job,
                         uint64_t& sceneHash) {
  ByteReader r(bytes, "farm job", path);
  r.open(kJobMagic);
  TraceBatch b;
  job = r.get<uint64_t>();
  sceneHash = r.get<uint64_t>();
  const uint32_t step = r.get<uint32_t>();
  if (step < 1 || step > 3) r.fail("unknown step " + std::to_string(step));
  b.step = TraceStep(step);
  b.floor = r.get<double>();
  b.litVoxel = r.get<double>();
  b.capBatches = r.get<int32_t>();
  b.options = getOptions(r);
  const uint64_t count = r.get<uint64_t>();
  if (count > r.left() / (4 + 24 + 4 + kProbeStateBytes)) r.fail("bad item count");
  b.items.resize(size_t(count));
  for (TraceItem& item : b.items) {
    item.index = r.get<uint32_t>();
    item.position.x = r.get<double>();
    item.position.y = r.get<double>();
    item.position.z = r.get<double>();
    item.stop = r.get<int32_t>();
    item.state = getProbeState(r);
  }
  r.finish();
  return b;
}

std::string encodeFarmResult(uint64_t job, int index, int count, const TraceBatch& b) {
  ByteWriter w;
  putResultHeader(w, kResultMagic, job, index, count, b.items.size());
  for (size_t k = size_t(index); k < b.items.size(); k += size_t(count)) {
    const TraceItem& item = b.items[k];
    w.put(item.index);
    putProbeState(w, item.state);
    w.put(item.intersectRays);
    w.put(item.occludedRays);
  }
  w.seal();
  return std::move(w.bytes);
}

void decodeFarmResult(const std::vector<char>& bytes, const std::string& path, uint64_t job, int index,
                      int count, TraceBatch& b) {
  ByteReader r(bytes, "farm result", path);
  checkResultHeader(r, kResultMagic, job, index, count, b.items.size());
  for (size_t k = size_t(index); k < b.items.size(); k += size_t(count)) {
    TraceItem& item = b.items[k];
    if (r.get<uint32_t>() != item.index) r.fail("holds another probe");
    item.state = getProbeState(r);
    item.intersectRays = r.get<uint64_t>();
    item.occludedRays = r.get<uint64_t>();
  }
  r.finish();
}

std::string encodeFarmPointJob(uint64_t job, uint64_t sceneHash, const ReferenceBatch& b) {
  ByteWriter w;
  w.bytes.assign(kPointJobMagic, kPointJobMagic + 8);
  w.put(job);
  w.put(sceneHash);
  putOptions(w, b.options);
  w.put(b.samples);
  w.put(uint64_t(b.items.size()));
  for (const ReferenceItem& item : b.items) {
    for (int k = 0; k < 3; ++k) w.put(item.position[k]);
    for (int k = 0; k < 3; ++k) w.put(item.normal[k]);
    w.put(item.seed);
  }
  w.seal();
  return std::move(w.bytes);
}

ReferenceBatch decodeFarmPointJob(const std::vector<char>& bytes, const std::string& path, uint64_t& job,
                                  uint64_t& sceneHash) {
  ByteReader r(bytes, "farm job", path);
  r.open(kPointJobMagic);
  ReferenceBatch b;
  job = r.get<uint64_t>();
  sceneHash = r.get<uint64_t>();
  b.options = getOptions(r);
  b.samples = r.get<int32_t>();
  const uint64_t count = r.get<uint64_t>();
  if (count > r.left() / (24 + 12 + 8)) r.fail("bad item count");
  b.items.resize(size_t(count));
  for (ReferenceItem& item : b.items) {
    for (int k = 0; k < 3; ++k) item.position[k] = r.get<double>();
    for (int k = 0; k < 3; ++k) item.normal[k] = r.get<float>();
    item.seed = r.get<uint64_t>();
  }
  r.finish();
  return b;
}

std::string encodeFarmPointResult(uint64_t job, int index, int count, const ReferenceBatch& b) {
  ByteWriter w;
  putResultHeader(w, kPointResultMagic, job, index, count, b.items.size());
  for (size_t k = size_t(index); k < b.items.size(); k += size_t(count)) {
    const ReferenceIrradiance& res = b.items[k].result;
    for (int c = 0; c < 3; ++c) w.put(res.irradiance[c]);
    for (int c = 0; c < 3; ++c) w.put(res.stderror[c]);
    w.put(int32_t(res.samples));
  }
  w.seal();
  return std::move(w.bytes);
}

void decodeFarmPointResult(const std::vector<char>& bytes, const std::string& path, uint64_t job, int index,
                           int count, ReferenceBatch& b) {
  ByteReader r(bytes, "farm result", path);
  checkResultHeader(r, kPointResultMagic, job, index, count, b.items.size());
  for (size_t k = size_t(index); k < b.items.size(); k += size_t(count)) {
    ReferenceIrradiance& res = b.items[k].result;
    for (int c = 0; c < 3; ++c) res.irradiance[c] = r.get<float>();
    for (int c = 0; c < 3; ++c) res.stderror[c] = r.get<float>();
    res.samples = r.get<int32_t>();
  }
  r.finish();
}

FileFarm::FileFarm(std::string dir, int workers, uint64_t sceneHash, double timeout, bool progress)
    : dir_(std::move(dir)),
      workers_(workers),
      sceneHash_(sceneHash),
      timeout_(timeout),
      progress_(progress),
      beat_([&] {
        if (workers < 1) throw UsageError("--workers must be at least 1");
        std::error_code ec;
        fs::create_directories(dir_, ec);
        if (ec) throw std::runtime_error("cannot create the farm directory " + dir_ + ": " + ec.message());
        for (const char* stale : {"/done", "/failed", "/job_0.batch"})
          if (fs::exists(dir_ + stale))
            throw InputError("the farm directory " + dir_ + " holds files of an earlier run (" +
                             std::string(stale + 1) + "): give an empty directory");
        return dir_ + "/merge.alive";
      }()) {
  for (int i = 0; i < workers_; ++i)
    watch_.emplace_back(dir_ + "/worker_" + std::to_string(i) + ".alive", timeout_);
}

FileFarm::~FileFarm() {
  if (!finished_) {
    std::string error;
    writeFileAtomic(dir_ + "/failed", "the merge stopped", &error);
  }
}

void FileFarm::finish() {
  writeAtomic(dir_ + "/done", "done");
  finished_ = true;
}

void FileFarm::trace(TraceBatch& batch) {
  const uint64_t job = uint64_t(jobs_++);
  items_ += batch.items.size();
  writeAtomic(jobPath(dir_, job), encodeFarmJob(job, sceneHash_, batch));
  collect(job, [&](const std::vector<char>& bytes, const std::string& path, int i) {
    decodeFarmResult(bytes, path, job, i, workers_, batch);
  });
}

void FileFarm::traceReferences(ReferenceBatch& batch) {
  const uint64_t job = uint64_t(jobs_++);
  points_ += batch.items.size();
  writeAtomic(jobPath(dir_, job), encodeFarmPointJob(job, sceneHash_, batch));
  collect(job, [&](const std::vector<char>& bytes, const std::string& path, int i) {
    decodeFarmPointResult(bytes, path, job, i, workers_, batch);
  });
}

void FileFarm::collect(uint64_t job,
                       const std::function<void(const std::vector<char>&, const std::string&, int)>& decode) {
  const double t0 = now();
  Progress shown("farm job " + std::to_string(job), uint64_t(workers_), "workers", progress_);
  std::vector<uint8_t> done(size_t(workers_), 0);
  int left = workers_;
  while (left > 0) {
    bool progressed = false;
    for (int i = 0; i < workers_; ++i) {
      if (done[size_t(i)]) continue;
      const std::string error = resultPath(dir_, job, i, ".error");
      if (const auto bytes = readIfThere(error))
        throw InputError("farm worker " + std::to_string(i) + ": " +
                         std::string(bytes->begin(), bytes->end()));
      const std::string path = resultPath(dir_, job, i, ".result");
      if (const auto bytes = readIfThere(path)) {
        decode(*bytes, path, i);
        shown.advance();
        done[size_t(i)] = 1;
        --left;
        progressed = true;
        continue;
      }
      if (!watch_[size_t(i)].alive())
        throw std::runtime_error("farm worker " + std::to_string(i) + " of " + std::to_string(workers_) +
                                 " gave no sign of life for " +
                                 std::to_string(int(watch_[size_t(i)].silentSeconds())) + " s (" + dir_ +
                                 "/worker_" + std::to_string(i) + ".alive; is `tetraprobe worker` running?)");
    }
    if (!progressed && left > 0) std::this_thread::sleep_for(kPoll);
  }
  std::error_code ec;
  fs::remove(jobPath(dir_, job), ec);
  for (int i = 0; i < workers_; ++i) fs::remove(resultPath(dir_, job, i, ".result"), ec);
  waitSeconds_ += now() - t0;
}

int runFarmWorker(const SceneTracer& tracer, uint64_t sceneHash, const std::string& dir, int index, int count,
                  int threads, double timeout, bool progress) {
  if (count < 1 || index < 0 || index >= count) throw UsageError("--index must be I/N with 0 <= I < N");
  std::error_code ec;
  fs::create_directories(dir, ec);
  Heartbeat beat(dir + "/worker_" + std::to_string(index) + ".alive");
  PeerWatch merge(dir + "/merge.alive", timeout);
  TraceRunner runner(tracer);
  uint64_t job = 0;
  auto checkJob = [&](uint64_t stored, uint64_t hash) {
    if (stored != job)
      throw InputError("farm job " + jobPath(dir, job) + " is numbered " + std::to_string(stored));
    if (hash != sceneHash)
      throw InputError("the merge baked another scene than this worker loaded (content hash)");
  };
  for (;;) {
    const std::string path = jobPath(dir, job);
    if (const auto bytes = readIfThere(path)) {
      uint64_t stored = 0, hash = 0;
      try {
        const bool points = bytes->size() >= 8 && std::memcmp(bytes->data(), kPointJobMagic, 8) == 0;
        const Progress shown("farm job " + std::to_string(job), 0, "", progress);
        if (points) {
          ReferenceBatch batch = decodeFarmPointJob(*bytes, path, stored, hash);
          checkJob(stored, hash);
          runShare(batch, index, count,
                   [&](ReferenceBatch& mine) { traceReferences(tracer, mine, threads); });
          writeAtomic(resultPath(dir, job, index, ".result"),
                      encodeFarmPointResult(job, index, count, batch));
        } else {
          TraceBatch batch = decodeFarmJob(*bytes, path, stored, hash);
          checkJob(stored, hash);
          runShare(batch, index, count, [&](TraceBatch& mine) { runner.run(mine, threads); });
          writeAtomic(resultPath(dir, job, index, ".result"), encodeFarmResult(job, index, count, batch));
        }
      } catch (const std::exception& e) {
        std::string error;
        writeFileAtomic(resultPath(dir, job, index, ".error"), e.what(), &error);
        throw;
      }
      ++job;
      continue;
    }
    if (fs::exists(dir + "/done")) return int(job);
    if (fs::exists(dir + "/failed")) throw std::runtime_error("the merge stopped (" + dir + "/failed)");
    if (!merge.alive())
      throw std::runtime_error("the merge gave no sign of life for " +
                               std::to_string(int(merge.silentSeconds())) + " s (" + dir + "/merge.alive)");
    std::this_thread::sleep_for(kPoll);
  }
}

}  // namespace tetraprobe::cli
