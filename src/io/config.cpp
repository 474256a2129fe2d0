#include "vesph/io/config.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

namespace vesph {
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
  return os.str();
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

// Splits "a.b[2].c" into segments; an index segment is "[2]".
std::vector<std::string> splitPath(const std::string& p) {
  std::vector<std::string> out;
  std::string cur;
  for (std::size_t k = 0; k < p.size(); ++k) {
    const char c = p[k];
    if (c == '.') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else if (c == '[') {
      if (!cur.empty()) out.push_back(cur);
      cur = "[";
    } else if (c == ']') {
      cur += ']';
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

}  // namespace

Config Config::fromString(const std::string& text, const std::string& label,
                          const std::vector<std::string>& overrides) {
  Config c;
  c.file_ = label;
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
  std::ifstream in(file);
  if (!in) throw InputError(file + ": cannot open the scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  return fromString(ss.str(), file, overrides);
}

void Config::applyOverride(const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("--set '" + assignment + "': expected KEY=VALUE, e.g. --set fluid.viscosity=1e-3");
  const std::string key = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  toml::table parsed;
  bool is_toml = true;
  try {
    parsed = toml::parse("v = " + text);
  } catch (const toml::parse_error&) {
    is_toml = false;
  }
  const auto segs = splitPath(key);
  if (segs.empty()) throw InputError("--set '" + assignment + "': empty key");
  toml::node* cur = &table_;
  for (std::size_t s = 0; s + 1 < segs.size(); ++s) {
    const std::string& g = segs[s];
    if (g.front() == '[') {
      auto* arr = cur->as_array();
      const std::size_t idx = std::stoul(g.substr(1, g.size() - 2));
      if (!arr || idx >= arr->size())
        throw InputError("--set '" + assignment + "': no array element " + g + " at that key");
      cur = arr->get(idx);
    } else {
      auto* t = cur->as_table();
      if (!t) throw InputError("--set '" + assignment + "': '" + g + "' is not inside a table");
      if (!t->contains(g)) t->insert(g, toml::table{});
      cur = t->get(g);
    }
  }
  const std::string& last = segs.back();
  auto* t = cur->as_table();
  if (!t || last.front() == '[')
    throw InputError("--set '" + assignment + "': the key must name a table entry");
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
      std::string msg = file_ + ": unknown key '" + full + "'" + lineOf(&v);
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
    ta = toml::parse(a);
    tb = toml::parse(b);
  } catch (const toml::parse_error& e) {
    return std::string("(unreadable scene: ") + std::string(e.description()) + ")";
  }
  return firstDifference(ta, tb, "", free);
}

}  // namespace vesph
