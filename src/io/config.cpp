#include "vesph/io/config.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace vesph {

std::string clipForMessage(const std::string& text, std::size_t max_chars) {
  if (text.size() <= max_chars) return text;
  std::size_t cut = max_chars;
  // Do not split a UTF-8 sequence: back off over continuation bytes (10xxxxxx).
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  return text.substr(0, cut) + "\u2026 (" + std::to_string(text.size()) + " characters)";
}

namespace {

bool isBareKeyChar(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}

// Advances i past the string starting at text[i] (a quote); counts the newlines of multi-line
// strings into line. An unterminated string ends at the end of its line (the parser reports it).
void skipTomlString(const std::string& text, std::size_t& i, std::size_t& line) {
  const char q = text[i];
  const std::size_t n = text.size();
  if (text.compare(i, 3, std::string(3, q)) == 0) {
    for (i += 3; i < n; ++i) {
      if (text[i] == '\\' && q == '"') {
        ++i;
        if (i < n && text[i] == '\n') ++line;
        continue;
      }
      if (text[i] == '\n') ++line;
      if (text.compare(i, 3, std::string(3, q)) == 0) {
        i += 3;
        while (i < n && text[i] == q) ++i;  // up to two quotes may close the content
        return;
      }
    }
    return;
  }
  for (++i; i < n && text[i] != '\n'; ++i) {
    if (text[i] == '\\' && q == '"') {
      if (i + 1 < n && text[i + 1] != '\n') ++i;
      continue;
    }
    if (text[i] == q) {
      ++i;
      return;
    }
  }
}

}  // namespace

void checkSceneText(const std::string& text, const std::string& label) {
  if (text.size() > kMaxSceneBytes)
    throw InputError(label + ": " + std::to_string(text.size()) + " bytes, larger than the " +
                     std::to_string(kMaxSceneBytes >> 20) + " MiB a scene file may have");
  // A lexical pass (strings and comments skipped) over the keys and brackets: the TOML library
  // recurses once per key part and per nested array or inline table, so absurd nesting would
  // overflow the stack inside it; no scene needs more than a few levels (docs/user-guide.md §3).
  std::vector<char> open;  // '[' or '{' opened in values
  bool key_expected = true;
  std::size_t line = 1, i = 0, header_parts = 0;
  const std::size_t n = text.size();
  while (i < n) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      ++i;
      if (open.empty()) key_expected = true;
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r') {
      ++i;
      continue;
    }
    if (c == '#') {
      while (i < n && text[i] != '\n') ++i;
      continue;
    }
    if (key_expected) {
      const bool header = open.empty() && c == '[';
      if (header) i += text.compare(i, 2, "[[") == 0 ? 2 : 1;
      std::size_t parts = 0;
      while (i < n) {
        const char d = text[i];
        if (d == ' ' || d == '\t' || d == '.') {
          ++i;
        } else if (d == '"' || d == '\'') {
          skipTomlString(text, i, line);
          ++parts;
        } else if (isBareKeyChar(d)) {
          while (i < n && isBareKeyChar(text[i])) ++i;
          ++parts;
        } else {
          break;
        }
      }
      // Counted as the resolved scene will write the key again: a header's parts and the
      // dotted key below it as one header path, a dotted key in an inline table as nested
      // inline tables (so that every accepted scene's resolved text is accepted as well).
      if (header) header_parts = parts;
      const std::size_t path = header ? parts : open.empty() ? header_parts + parts : parts;
      if (path > kMaxKeyParts)
        throw InputError(label + ": a key of " + std::to_string(path) + " dotted parts (line " + std::to_string(line) +
                         "); scene keys have at most " + std::to_string(kMaxKeyParts));
      if (!open.empty() && parts > 0 && open.size() + parts - 1 > kMaxValueNesting)
        throw InputError(label + ": arrays or inline tables nested more than " + std::to_string(kMaxValueNesting) +
                         " deep (line " + std::to_string(line) + ")");
      key_expected = false;
      continue;
    }
    if (c == '"' || c == '\'') {
      skipTomlString(text, i, line);
      continue;
    }
    if (c == '[' || c == '{') {
      open.push_back(c);
      if (open.size() > kMaxValueNesting)
        throw InputError(label + ": arrays or inline tables nested more than " + std::to_string(kMaxValueNesting) +
                         " deep (line " + std::to_string(line) + ")");
      key_expected = c == '{';
    } else if (c == ']' || c == '}') {
      if (!open.empty()) open.pop_back();
    } else if (c == ',') {
      key_expected = !open.empty() && open.back() == '{';
    }
    ++i;
  }
}

namespace {

std::string describe(const toml::node* n) {
  if (!n) return "nothing";
  std::ostringstream os;
  if (n->is_string()) os << '"' << n->as_string()->get() << '"';
  else if (n->is_table()) os << "a table";
  else if (n->is_array()) os << "an array " << *n->as_array();
  else if (n->is_boolean()) os << (n->as_boolean()->get() ? "true" : "false");
  else if (n->is_integer()) os << n->as_integer()->get();
  else if (n->is_floating_point()) os << n->as_floating_point()->get();
  else os << "a value of another type";
  return clipForMessage(os.str());
}

std::string lineOf(const toml::node* n) {
  if (!n || !n->source().begin) return "";
  return " (line " + std::to_string(n->source().begin.line) + ")";
}

std::optional<double> asNumber(const toml::node* n) {
  if (!n) return std::nullopt;
  if (auto f = n->as_floating_point()) return f->get();
  if (auto i = n->as_integer()) return static_cast<double>(i->get());
  return std::nullopt;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (std::size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + v[k];
  return s;
}

// Splits the key of a --set, "a.b[2].c", into segments; an index segment is "[2]". Anything
// else in brackets ("[abc]", "[]", "[[0]]", an index beyond any array) is refused, naming the
// assignment (shown as `shown`).
std::vector<std::string> splitPath(const std::string& p, const std::string& shown) {
  auto refuse = [&](const std::string& why) { throw InputError("--set '" + shown + "': " + why); };
  std::vector<std::string> out;
  std::string cur;
  for (std::size_t k = 0; k < p.size(); ++k) {
    const char c = p[k];
    if (c == '.') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else if (c == '[') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
      const std::size_t close = p.find(']', k + 1);
      const std::string digits = close == std::string::npos ? p.substr(k + 1) : p.substr(k + 1, close - k - 1);
      if (close == std::string::npos || digits.empty() || digits.size() > 9 ||
          digits.find_first_not_of("0123456789") != std::string::npos)
        refuse("'[" + clipForMessage(digits, 20) +
               (close == std::string::npos ? "" : "]") + "' is not an array index (expected [N], N = 0, 1, ...)");
      out.push_back("[" + digits + "]");
      k = close;
    } else if (c == ']') {
      refuse("a ']' without its '['");
    } else {
      cur += c;
    }
    if (out.size() > kMaxKeyParts) refuse("more than " + std::to_string(kMaxKeyParts) + " key parts");
  }
  if (!cur.empty()) out.push_back(cur);
  if (out.size() > kMaxKeyParts) refuse("more than " + std::to_string(kMaxKeyParts) + " key parts");
  return out;
}

}  // namespace

Config Config::fromString(const std::string& text, const std::string& label,
                          const std::vector<std::string>& overrides) {
  Config c;
  c.file_ = label;
  checkSceneText(text, label);
  try {
    c.table_ = toml::parse(text, label);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << label << ": not valid TOML: " << e.description() << " (line " << e.source().begin.line
       << ", column " << e.source().begin.column << ")";
    throw InputError(os.str());
  }
  for (const auto& o : overrides) c.applyOverride(o);
  return c;
}

Config Config::fromFile(const std::string& file, const std::vector<std::string>& overrides) {
  // Special files are named as such before anything is read: a directory opens as an empty
  // stream, and /dev/zero never ends.
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (std::filesystem::is_directory(status)) throw InputError(file + ": is a directory, not a scene file");
  if (std::filesystem::is_character_file(status) || std::filesystem::is_block_file(status))
    throw InputError(file + ": is a device, not a scene file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file + ": cannot open the scene file");
  // Read at most one byte more than a scene may have (pipes have no size to ask for).
  std::string text(kMaxSceneBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw InputError(file + ": cannot read the scene file");
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxSceneBytes)
    throw InputError(file + ": larger than the " + std::to_string(kMaxSceneBytes >> 20) + " MiB a scene file may have");
  if (text.empty()) throw InputError(file + ": the scene file is empty");
  return fromString(text, file, overrides);
}

void Config::applyOverride(const std::string& assignment) {
  const std::string shown = clipForMessage(assignment);
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("--set '" + shown + "': expected KEY=VALUE, e.g. --set fluid.viscosity=1e-3");
  const std::string key = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  const auto segs = splitPath(key, shown);
  if (segs.empty()) throw InputError("--set '" + shown + "': empty key");
  toml::table parsed;
  bool is_toml = true;
  checkSceneText("v = " + text, "--set '" + shown + "'");
  try {
    parsed = toml::parse("v = " + text);
  } catch (const toml::parse_error&) {
    is_toml = false;
  }
  toml::node* cur = &table_;
  for (std::size_t s = 0; s + 1 < segs.size(); ++s) {
    const std::string& g = segs[s];
    if (g.front() == '[') {
      auto* arr = cur->as_array();
      const std::size_t idx = std::stoul(g.substr(1, g.size() - 2));  // at most 9 digits (splitPath)
      if (!arr || idx >= arr->size())
        throw InputError("--set '" + shown + "': no array element " + g + " at that key");
      cur = arr->get(idx);
    } else {
      auto* t = cur->as_table();
      if (!t) throw InputError("--set '" + shown + "': '" + clipForMessage(g) + "' is not inside a table");
      if (!t->contains(g)) t->insert(g, toml::table{});
      cur = t->get(g);
    }
  }
  const std::string& last = segs.back();
  auto* t = cur->as_table();
  if (!t || last.front() == '[')
    throw InputError("--set '" + shown + "': the key must name a table entry");
  if (is_toml) t->insert_or_assign(last, *parsed.get("v"));
  else t->insert_or_assign(last, text);
}

ConfigTable Config::root() { return ConfigTable(*this, &table_, ""); }

void Config::checkTable(const toml::table& t, const std::string& path) const {
  const auto it = queried_.find(path);
  for (const auto& [k, v] : t) {
    const std::string key(k.str());
    const std::string full = path.empty() ? key : path + "." + key;
    if (it == queried_.end() || !it->second.count(key)) {
      std::string msg = file_ + ": unknown key '" + clipForMessage(full) + "'" + lineOf(&v);
      if (it != queried_.end() && !it->second.empty()) {
        std::vector<std::string> known(it->second.begin(), it->second.end());
        msg += "; valid keys " + (path.empty() ? std::string("at the top level") : "in [" + path + "]") +
               ": " + join(known);
      }
      throw InputError(msg);
    }
    if (auto* sub = v.as_table()) checkTable(*sub, full);
    if (auto* arr = v.as_array())
      for (std::size_t e = 0; e < arr->size(); ++e)
        if (auto* st = arr->get(e)->as_table()) checkTable(*st, full + "[" + std::to_string(e) + "]");
  }
}

void Config::rejectUnknownKeys() const { checkTable(table_, ""); }

std::string Config::resolvedToml() const {
  std::ostringstream os;
  os << table_;
  return os.str();
}

// ---------------------------------------------------------------------------------------

bool ConfigTable::has(std::string_view key) const { return t_->contains(key); }

toml::node* ConfigTable::node(std::string_view key) {
  cfg_->markQueried(path_, key);
  return t_->get(key);
}

void ConfigTable::fail(std::string_view key, const std::string& expected) const {
  const toml::node* n = t_->get(key);
  throw InputError(cfg_->file_ + ": " + keyPath(key) + ": expected " + expected + ", got " +
                   describe(n) + lineOf(n));
}

double ConfigTable::number(std::string_view key, std::optional<double> def, Bound bound,
                           std::string_view unit) {
  const std::string u = unit.empty() ? "" : " (" + std::string(unit) + ")";
  const std::string what = bound == Bound::positive      ? "a positive number"
                           : bound == Bound::nonnegative ? "a non-negative number"
                                                         : "a number";
  toml::node* n = node(key);
  if (!n) {
    if (!def) fail(key, what + u + " (this key is required)");
    t_->insert(key, *def);
    return *def;
  }
  const auto v = asNumber(n);
  if (!v || !std::isfinite(*v)) fail(key, what + u);
  if (bound == Bound::positive && !(*v > 0)) fail(key, what + u);
  if (bound == Bound::nonnegative && !(*v >= 0)) fail(key, what + u);
  return *v;
}

double ConfigTable::numberAtMost(std::string_view key, std::optional<double> def, Bound bound, double max,
                                 std::string_view unit) {
  const double v = number(key, def, bound, unit);
  if (v > max) {
    std::ostringstream what;
    what << (bound == Bound::positive ? "a positive number" : bound == Bound::nonnegative ? "a non-negative number" : "a number")
         << " of at most " << max << (unit.empty() ? "" : " (" + std::string(unit) + ")");
    fail(key, what.str());
  }
  return v;
}

std::optional<double> ConfigTable::optionalNumber(std::string_view key, Bound bound, std::string_view unit) {
  if (!t_->contains(key)) {
    markRead(key);
    return std::nullopt;
  }
  return number(key, std::nullopt, bound, unit);
}

double ConfigTable::numberIn(std::string_view key, std::optional<double> def, double lo, double hi,
                             std::string_view unit) {
  std::ostringstream what;
  what << "a number in [" << lo << ", " << hi << "]" << (unit.empty() ? "" : " (" + std::string(unit) + ")");
  toml::node* n = node(key);
  if (!n) {
    if (!def) fail(key, what.str() + " (this key is required)");
    t_->insert(key, *def);
    return *def;
  }
  const auto v = asNumber(n);
  if (!v || !(*v >= lo && *v <= hi)) fail(key, what.str());
  return *v;
}

long long ConfigTable::integer(std::string_view key, std::optional<long long> def, long long lo,
                               long long hi) {
  std::ostringstream what;
  what << "an integer in [" << lo << ", " << hi << "]";
  toml::node* n = node(key);
  if (!n) {
    if (!def) fail(key, what.str() + " (this key is required)");
    t_->insert(key, static_cast<int64_t>(*def));
    return *def;
  }
  auto* i = n->as_integer();
  if (!i || i->get() < lo || i->get() > hi) fail(key, what.str());
  return i->get();
}

bool ConfigTable::boolean(std::string_view key, std::optional<bool> def) {
  toml::node* n = node(key);
  if (!n) {
    if (!def) fail(key, "true or false (this key is required)");
    t_->insert(key, *def);
    return *def;
  }
  auto* b = n->as_boolean();
  if (!b) fail(key, "true or false");
  return b->get();
}

std::string ConfigTable::string(std::string_view key, std::optional<std::string> def) {
  toml::node* n = node(key);
  if (!n) {
    if (!def) fail(key, "a string (this key is required)");
    t_->insert(key, *def);
    return *def;
  }
  auto* s = n->as_string();
  if (!s) fail(key, "a string");
  return s->get();
}

std::string ConfigTable::choice(std::string_view key, std::optional<std::string> def,
                                const std::vector<std::string>& allowed) {
  toml::node* n = node(key);
  const std::string what = "one of: " + join(allowed);
  if (!n) {
    if (!def) fail(key, what + " (this key is required)");
    t_->insert(key, *def);
    return *def;
  }
  auto* s = n->as_string();
  if (!s) fail(key, what);
  for (const auto& a : allowed)
    if (a == s->get()) return a;
  fail(key, what);
}

std::vector<double> ConfigTable::numbers(std::string_view key, std::optional<std::vector<double>> def,
                                         std::size_t count, std::string_view unit) {
  const std::string what = (count ? "an array of " + std::to_string(count) + " numbers"
                                  : std::string("an array of numbers")) +
                           (unit.empty() ? "" : " (" + std::string(unit) + ")");
  toml::node* n = node(key);
  if (!n) {
    if (!def) fail(key, what + " (this key is required)");
    toml::array arr;
    for (double d : *def) arr.push_back(d);
    t_->insert(key, arr);
    return *def;
  }
  auto* arr = n->as_array();
  if (!arr || (count && arr->size() != count)) fail(key, what);
  std::vector<double> out;
  for (auto& e : *arr) {
    const auto v = asNumber(&e);
    if (!v || !std::isfinite(*v)) fail(key, what);
    out.push_back(*v);
  }
  return out;
}

std::vector<bool> ConfigTable::booleans(std::string_view key, std::optional<std::vector<bool>> def,
                                        std::size_t count) {
  const std::string what = "an array of " + std::to_string(count) + " booleans";
  toml::node* n = node(key);
  if (!n) {
    if (!def) fail(key, what + " (this key is required)");
    toml::array arr;
    for (bool b : *def) arr.push_back(b);
    t_->insert(key, arr);
    return *def;
  }
  auto* arr = n->as_array();
  if (!arr || arr->size() != count) fail(key, what);
  std::vector<bool> out;
  for (auto& e : *arr) {
    auto* b = e.as_boolean();
    if (!b) fail(key, what);
    out.push_back(b->get());
  }
  return out;
}

bool ConfigTable::isTable(std::string_view key) const {
  const toml::node* n = t_->get(key);
  return n && n->is_table();
}

ConfigTable ConfigTable::table(std::string_view key, bool create) {
  toml::node* n = node(key);
  if (!n) {
    if (!create) fail(key, "a table (this table is required)");
    t_->insert(key, toml::table{});
    n = t_->get(key);
  }
  auto* t = n->as_table();
  if (!t) fail(key, "a table");
  return ConfigTable(*cfg_, t, keyPath(key));
}

std::vector<ConfigTable> ConfigTable::tableArray(std::string_view key) {
  toml::node* n = node(key);
  std::vector<ConfigTable> out;
  if (!n) return out;
  auto* arr = n->as_array();
  if (!arr) fail(key, "an array of tables ([[" + keyPath(key) + "]])");
  for (std::size_t e = 0; e < arr->size(); ++e) {
    auto* t = arr->get(e)->as_table();
    if (!t) fail(key, "an array of tables ([[" + keyPath(key) + "]])");
    out.emplace_back(*cfg_, t, keyPath(key) + "[" + std::to_string(e) + "]");
  }
  return out;
}

std::vector<std::string> ConfigTable::keys() const {
  std::vector<std::string> out;
  for (const auto& [k, v] : *t_) out.emplace_back(k.str());
  return out;
}

namespace {
std::string firstDifference(const toml::table& a, const toml::table& b, const std::string& path,
                            const std::set<std::string>& free) {
  std::set<std::string> keys;
  for (const auto& [k, v] : a) keys.insert(std::string(k.str()));
  for (const auto& [k, v] : b) keys.insert(std::string(k.str()));
  for (const std::string& k : keys) {
    if (path.empty() && free.count(k)) continue;
    const std::string here = path.empty() ? k : path + "." + k;
    const toml::node* x = a.get(k);
    const toml::node* y = b.get(k);
    if (!x || !y) return here;
    if (x->is_table() && y->is_table()) {
      const std::string d = firstDifference(*x->as_table(), *y->as_table(), here, free);
      if (!d.empty()) return d;
    } else if (toml::node_view<const toml::node>{x} != toml::node_view<const toml::node>{y}) {
      return here;
    }
  }
  return {};
}
}  // namespace

std::string firstSceneDifference(const std::string& a, const std::string& b, const std::set<std::string>& free) {
  toml::table ta, tb;
  try {
    checkSceneText(a, "the stored scene");
    checkSceneText(b, "the scene");
    ta = toml::parse(a);
    tb = toml::parse(b);
  } catch (const toml::parse_error& e) {
    return std::string("(unreadable scene: ") + std::string(e.description()) + ")";
  } catch (const InputError& e) {
    return std::string("(unreadable scene: ") + e.what() + ")";
  }
  return firstDifference(ta, tb, "", free);
}

}  // namespace vesph
