#pragma once
// Strict reading of scene files (TOML). Every value is read through a ConfigTable, which
// checks its type and range, records the default it applied (so `vesph check` prints the
// fully resolved scene), and remembers which keys were asked for; afterwards
// Config::rejectUnknownKeys() reports any key nobody asked for, with the valid ones.
// Errors are InputError with "FILE: KEY: expected ..., got ... (line N)".
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "vesph/core/types.hpp"

namespace vesph {

class ConfigTable;

// Limits on scene text (files, --set values, the scene stored in an output file), far above what
// any scene needs: beyond them the TOML library would exhaust memory or overflow the stack.
inline constexpr std::size_t kMaxSceneBytes = std::size_t{4} << 20;  // 4 MiB
inline constexpr std::size_t kMaxKeyParts = 16;      // parts of a dotted key or table header
inline constexpr std::size_t kMaxValueNesting = 16;  // arrays and inline tables inside each other

// Throws InputError naming `label` when the text exceeds kMaxSceneBytes, a key or table header
// has more than kMaxKeyParts parts, or arrays/inline tables nest deeper than kMaxValueNesting.
void checkSceneText(const std::string& text, const std::string& label);

// The text for an error message: cut after max_chars bytes (at a UTF-8 boundary), with an
// ellipsis and the full length.
std::string clipForMessage(const std::string& text, std::size_t max_chars = 80);

// Compares two resolved scenes (TOML text, as Config::resolvedToml writes them) and returns the
// dotted path of the first key whose value differs, or that one has and the other lacks,
// outside the top-level tables named in `free`; empty when they agree. `vesph run --resume`
// uses it: only [time], [output], [checks] and [integrator] may change between the segments.
std::string firstSceneDifference(const std::string& a, const std::string& b, const std::set<std::string>& free);

class Config {
 public:
  // Parses FILE and applies --set overrides ("dotted.key=value", the value in TOML syntax;
  // a value that is not valid TOML is taken as a string).
  static Config fromFile(const std::string& file, const std::vector<std::string>& overrides = {});
  static Config fromString(const std::string& text, const std::string& label,
                           const std::vector<std::string>& overrides = {});

  ConfigTable root();
  void rejectUnknownKeys() const;
  std::string resolvedToml() const;
  const std::string& file() const { return file_; }

 private:
  friend class ConfigTable;
  void applyOverride(const std::string& assignment);
  void markQueried(const std::string& table_path, std::string_view key) {
    queried_[table_path].insert(std::string(key));
  }
  void checkTable(const toml::table& t, const std::string& path) const;

  std::string file_;
  toml::table table_;
  std::map<std::string, std::set<std::string>> queried_;
};

enum class Bound { any, positive, nonnegative };

class ConfigTable {
 public:
  ConfigTable(Config& cfg, toml::table* t, std::string path) : cfg_(&cfg), t_(t), path_(std::move(path)) {}

  bool has(std::string_view key) const;
  const std::string& path() const { return path_; }
  std::string keyPath(std::string_view key) const { return path_.empty() ? std::string(key) : path_ + "." + std::string(key); }

  double number(std::string_view key, std::optional<double> def, Bound bound = Bound::any,
                std::string_view unit = "");
  // number() with an upper limit as well: for coefficients whose absurd values would pass every
  // other check and then drive the time step to zero (docs/user-guide.md lists the limits).
  double numberAtMost(std::string_view key, std::optional<double> def, Bound bound, double max,
                      std::string_view unit = "");
  // A number without a default: std::nullopt when the key is absent (nothing is inserted).
  std::optional<double> optionalNumber(std::string_view key, Bound bound = Bound::any, std::string_view unit = "");
  double numberIn(std::string_view key, std::optional<double> def, double lo, double hi,
                  std::string_view unit = "");
  long long integer(std::string_view key, std::optional<long long> def, long long lo, long long hi);
  bool boolean(std::string_view key, std::optional<bool> def);
  std::string string(std::string_view key, std::optional<std::string> def);
  std::string choice(std::string_view key, std::optional<std::string> def,
                     const std::vector<std::string>& allowed);
  std::vector<double> numbers(std::string_view key, std::optional<std::vector<double>> def,
                              std::size_t count /* 0 = any length */, std::string_view unit = "");
  std::vector<bool> booleans(std::string_view key, std::optional<std::vector<bool>> def,
                             std::size_t count);
  template <int D>
  Vec<D> vector(std::string_view key, std::optional<Vec<D>> def, std::string_view unit = "") {
    std::optional<std::vector<double>> d;
    if (def) d = std::vector<double>(def->data(), def->data() + D);
    const auto v = numbers(key, d, D, unit);
    Vec<D> out;
    for (int a = 0; a < D; ++a) out[a] = v[a];
    return out;
  }

  // A required coordinate unit vector +-e_axis (the only directions a lattice box can face):
  // returns {axis, sign}; otherwise fails with `expected`.
  template <int D>
  std::pair<int, double> coordinateAxis(std::string_view key, const std::string& expected) {
    const Vec<D> v = vector<D>(key, std::nullopt);
    int axis = -1, nonzero = 0;
    for (int a = 0; a < D; ++a)
      if (v[a] != 0.0) {
        ++nonzero;
        axis = a;
      }
    if (nonzero != 1 || std::abs(std::abs(v[axis]) - 1.0) > 1e-12) fail(key, expected);
    return {axis, v[axis] > 0 ? 1.0 : -1.0};
  }

  // A sub-table; with create, an absent one is created empty (so its defaults show up).
  ConfigTable table(std::string_view key, bool create = true);
  bool isTable(std::string_view key) const;
  std::vector<ConfigTable> tableArray(std::string_view key);
  // Keys present in this table (marks none as read).
  std::vector<std::string> keys() const;
  void markRead(std::string_view key) { cfg_->markQueried(path_, key); }

  [[noreturn]] void fail(std::string_view key, const std::string& expected) const;

 private:
  toml::node* node(std::string_view key);
  Config* cfg_;
  toml::table* t_;
  std::string path_;
};

}  // namespace vesph
