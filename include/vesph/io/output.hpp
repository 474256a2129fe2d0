#pragma once
// Output format "vesph-1" (docs/architecture.md "Output"; docs/user-guide.md): DIR/<name>.h5 with one group per frame and
// the per-step diagnostics, DIR/<name>.xdmf describing the frames for ParaView/VisIt, and
// DIR/summary.json. The HDF5 file is flushed after every frame and the XDMF file replaced
// atomically, so whatever was written before a failure or an interruption stays readable.
#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "vesph/core/domain.hpp"
#include "vesph/core/particles.hpp"

namespace vesph {

// One row per accepted step. `extra` holds the columns of post-step hooks (the ISPH
// projection: solver iterations, residual, times, divergence), named by
// FileAttributes::extra_columns; scenes without such a hook write none.
inline constexpr std::size_t kMaxExtraDiagnostics = 16;  // ISPH with cleaning (11) + inflow/outflow (3) = 14
struct DiagnosticsRow {
  double time, dt, kinetic_energy, mass, max_speed, max_density_deviation;
  std::array<double, kMaxExtraDiagnostics> extra{};
};

// A gauge's series in /gauges/<name> (docs/user-guide.md "Output"): a group with attributes
// type and position and one 1-D float64 dataset per column, "time" first, one row per frame.
struct GaugeSeries {
  std::string name, type;
  std::vector<double> position;      // m (the point, or the line's foot; empty for a front)
  std::vector<std::string> columns;  // "time", then the measured values
};

struct FileAttributes {
  int dim = 2;
  std::string scene_toml;
  double dx = 0, h = 0;
  std::string kernel;
  std::vector<std::string> extra_columns;  // diagnostics columns after the standard ones
  std::vector<GaugeSeries> gauges;         // none: the file has no /gauges group
};

// The restart point of a run (`vesph run --resume`), kept in /checkpoint of the HDF5 file and
// replaced with every frame: the ODE state vector of the integrator (positions | densities |
// velocities | evolving fields, StateSegments) at the frame's time, the ids of the particle set
// it belongs to, and the run's totals so far, so that a resumed run reports the whole run.
struct Checkpoint {
  double time = 0;                  // s, the time of the frame it was written with
  std::int64_t step = 0;            // accepted steps so far
  std::uint64_t rhs_evals = 0, rejected_steps = 0, neighbour_builds = 0;
  double wall_seconds = 0;          // s, wall-clock time of the run so far (all segments)
  double max_density_deviation = 0; // largest over the accepted steps so far
  std::uint64_t resumes = 0;        // how often the run was resumed before
  std::vector<double> state;
  std::vector<std::uint64_t> id;
  // Arrays carried between steps, by name: "<effect or hook>.<array>" (saveCarried),
  // "integrator.carried", and for a changing particle set "particles.*", "system.next_id".
  std::vector<std::pair<std::string, std::vector<double>>> arrays;
  // As read from a file: its "checksum" attribute (checkpointChecksum when written); absent in
  // files of vesph versions before it.
  std::optional<std::uint64_t> checksum;
  // The carried array of that name, or nullptr when the checkpoint has none.
  const std::vector<double>* find(const std::string& name) const {
    for (const auto& [aname, values] : arrays)
      if (aname == name) return &values;
    return nullptr;
  }
};

// What `--resume` needs from an existing output: the resolved scene the file was written with
// and its checkpoint. Throws InputError when DIR/<name>.h5 is missing, is not a vesph-1 file or
// holds no checkpoint (files of vesph versions before checkpoints).
struct ResumeSource {
  std::string scene_toml;
  Checkpoint checkpoint;
  std::vector<double> frame_times;  // of the file's complete frames (those with a time)
};

// FNV-1a (64 bit) over the checkpoint's state, ids and carried arrays (by name, in name order:
// the order a file lists them), their bytes as stored (little-endian IEEE doubles, uint64).
// Written with every checkpoint and verified on --resume: a flipped byte is refused.
std::uint64_t checkpointChecksum(const Checkpoint& c);
ResumeSource readResumeSource(const std::string& dir, const std::string& name);

// A write that failed (a full disk, a file size limit): the file is closed, what was flushed
// before stays readable. In a file written together every process throws it together.
class OutputFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A file written by every process of a run across processes together (docs/architecture.md
// "Distributed runs": parallel HDF5 over MPI-IO). Every process makes each OutputWriter call in
// the same order with the same arguments, except that it passes only its share of the particles
// and where their rows lie: the file holds every moving particle first (rows
// [0, moving_total)), then every fixed one, exactly as a serial run's does. The diagnostics and
// gauge rows (the same on every process) are written by process 0.
struct FrameRows {
  std::uint64_t moving_offset = 0, moving_total = 0;  // this process's moving particles' rows
  std::uint64_t fixed_offset = 0, fixed_total = 0;    // its fixed particles', after the moving rows
};
// A process's part of a checkpoint: its moving particles' state values are the rows
// [moving_offset, moving_offset + n) of each state segment (StateSegments: positions |
// densities | velocities | evolving fields, `segment_widths` values per particle each); its ids
// are the frame's rows. A carried array is laid out as the state (the integrator's rate), as
// the frame's rows with a number of values per particle (`particle_arrays`: a changing
// particle set's positions, velocities, masses), or else is the same on every process (the
// particle count, the hooks' totals; process 0 writes it).
struct CheckpointRows {
  FrameRows rows;
  std::vector<std::size_t> segment_widths;
  std::vector<std::string> state_arrays;                              // laid out as the state
  std::vector<std::pair<std::string, std::size_t>> particle_arrays;  // name, values per particle
  // The layout of a carried array: 0 the state's; > 0 the frame rows' with that many values per
  // particle; -1 the same on every process.
  long layoutOf(const std::string& name) const {
    for (const std::string& n : state_arrays)
      if (n == name) return 0;
    for (const auto& [n, cols] : particle_arrays)
      if (n == name) return static_cast<long>(cols);
    return -1;
  }
};

// The checksum of a checkpoint whose values are spread over processes, each holding `part`, its
// share of the rows (CheckpointRows): the same value checkpointChecksum gives for the whole
// checkpoint, on every process. Collective over *communicator (an MPI_Comm).
std::uint64_t checkpointChecksum(const Checkpoint& part, const CheckpointRows& rows, const void* communicator);

template <int D>
class OutputWriter {
 public:
  // `communicator` (an MPI_Comm*): the processes of a run across processes, which then write the
  // file together (FrameRows); null for a serial run.
  OutputWriter(const std::string& dir, const std::string& name, const FileAttributes& attrs,
               const void* communicator = nullptr);
  // Reopens the file of a run to go on from its checkpoint at resume_time: the frames after
  // that time and the diagnostics rows after it are dropped (the resumed run writes them
  // again), the scene attribute is replaced by attrs.scene_toml, and frames and rows are then
  // appended. The diagnostics columns must be those of attrs.
  OutputWriter(const std::string& dir, const std::string& name, const FileAttributes& attrs, double resume_time,
               const void* communicator = nullptr);
  ~OutputWriter();
  OutputWriter(const OutputWriter&) = delete;
  OutputWriter& operator=(const OutputWriter&) = delete;

  // Writes a frame of the particle set (positions as it holds them: wrapped into the periodic
  // box) and the diagnostics rows gathered since the last frame; flushes everything to disk.
  // In a file written together, `p` is this process's share and `rows` says where it goes.
  void writeFrame(double time, std::int64_t step, const ParticleSet<D>& p,
                  const std::vector<DiagnosticsRow>& new_rows, const FrameRows* rows = nullptr);
  // Appends one row per gauge (values in the order of FileAttributes::gauges' columns, time
  // first); written to disk with the next frame's flush. Call it before writeFrame.
  void appendGauges(const std::vector<std::vector<double>>& rows);
  // Replaces the checkpoint (/checkpoint); flushed. Called after the frame of the same state.
  // In a file written together, `c` holds this process's rows of the state, ids and arrays.
  void writeCheckpoint(const Checkpoint& c, const CheckpointRows* rows = nullptr);
  std::size_t frames() const { return frames_.size(); }
  const std::string& h5Path() const { return h5_path_; }
  const std::string& xdmfPath() const { return xdmf_path_; }

 private:
  struct FrameInfo {
    std::string group;
    double time;
    std::size_t n;
    bool stress, free_surface, pressure, stress_zz;
  };
  void appendDiagnostics(const std::vector<DiagnosticsRow>& rows);
  // The /gauges group of a new file; on --resume its rows after the resume time are dropped
  // (the resumed run writes them again with its frames). src/io/gauge_output.cpp.
  void createGauges();
  void truncateGauges(double resume_time);
  void writeXdmf() const;
  void reopen(const FileAttributes& attrs, double resume_time);  // the resuming constructor's work
  // Closes the file (once); every later write fails.
  void close();
  // H5Fflush; on failure closes the file and throws through failed().
  void flush(const char* what);
  // Closes the file and throws a runtime_error: WHAT could not be written, the room left on the
  // disk when little is, and the last frame that is intact.
  [[noreturn]] void failed(const std::string& what);
  // Throws (file closed, nothing written) when the disk of the output directory has less room
  // than `bytes` plus HDF5's metadata.
  void ensureSpace(std::size_t bytes, const char* what);
  std::string noSpaceNote() const;
  // A file written together: opened by every process (MPI-IO); whether this process writes the
  // rows every process holds alike (the diagnostics, the gauges: process 0); every process's
  // `ok` agreed on (false when any is false).
  void openAccess(std::int64_t fapl) const;
  bool writesSharedRows() const { return rank_ == 0; }
  // Writes rows every process holds alike (fspace: their selection in dataset d): process 0's,
  // in one collective transfer that every process makes (so that every process takes part in
  // allocating the chunks it needs, also in a file a serial run began); serially, a plain write.
  void writeSharedRows(std::int64_t d, std::int64_t mspace, std::int64_t fspace, const void* data, const char* what,
                       std::int64_t mem_type = -1) const;
  // A file that a serial run (or an older vesph) began, continued by several processes: its
  // extensible datasets, whose chunks a serial run allocates as it first writes them, are made
  // again as processes writing together make them (allocated as they are created and
  // extended: otherwise each process would allocate on its own). Collective; values kept.
  void remakeForProcesses();
  bool agreed(bool ok) const;

  const void* communicator_ = nullptr;
  int rank_ = 0;

  std::string dir_, name_, h5_path_, xdmf_path_;
  std::int64_t file_ = -1;
  std::vector<FrameInfo> frames_;
  std::size_t diag_rows_ = 0;
  std::vector<std::string> extra_columns_;
  std::vector<GaugeSeries> gauges_;
  std::size_t gauge_rows_ = 0;
};

// Writes DIR/summary.json atomically.
void writeSummary(const std::string& dir, const nlohmann::json& summary);

}  // namespace vesph
