#pragma once
// Output format "vesph-1" (DESIGN.md "Output"): DIR/<name>.h5 with one group per frame and
// the per-step diagnostics, DIR/<name>.xdmf describing the frames for ParaView/VisIt, and
// DIR/summary.json. The HDF5 file is flushed after every frame and the XDMF file replaced
// atomically, so whatever was written before a failure or an interruption stays readable.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "vesph/core/domain.hpp"
#include "vesph/core/particles.hpp"

namespace vesph {

// One row per accepted step. `extra` holds the columns of post-step hooks (the ISPH
// projection: solver iterations, residual, times, divergence), named by
// FileAttributes::extra_columns; scenes without such a hook write none.
inline constexpr std::size_t kMaxExtraDiagnostics = 12;
struct DiagnosticsRow {
  double time, dt, kinetic_energy, mass, max_speed, max_density_deviation;
  std::array<double, kMaxExtraDiagnostics> extra{};
};

struct FileAttributes {
  int dim = 2;
  std::string scene_toml;
  double dx = 0, h = 0;
  std::string kernel;
  std::vector<std::string> extra_columns;  // diagnostics columns after the standard ones
};

template <int D>
class OutputWriter {
 public:
  OutputWriter(const std::string& dir, const std::string& name, const FileAttributes& attrs);
  ~OutputWriter();
  OutputWriter(const OutputWriter&) = delete;
  OutputWriter& operator=(const OutputWriter&) = delete;

  // Writes a frame of the particle set (positions as it holds them: wrapped into the periodic
  // box) and the diagnostics rows gathered since the last frame; flushes everything to disk.
  void writeFrame(double time, std::int64_t step, const ParticleSet<D>& p,
                  const std::vector<DiagnosticsRow>& new_rows);
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
  void writeXdmf() const;

  std::string dir_, name_, h5_path_, xdmf_path_;
  std::int64_t file_ = -1;
  std::vector<FrameInfo> frames_;
  std::size_t diag_rows_ = 0;
  std::vector<std::string> extra_columns_;
};

// Writes DIR/summary.json atomically.
void writeSummary(const std::string& dir, const nlohmann::json& summary);

}  // namespace vesph
