// Bad input and faults (issue 37): absurd scene text, malformed --set keys, absurd
// coefficients, two constitutive models, a huge domain around few particles, malformed
// checkpoints; and fuzz targets for the scene parser and the checkpoint reader. Every outcome
// must be a result or an InputError: no crash, no other exception, no hang.
//
// The fuzz cases run a bounded number of mutations with a fixed seed (seconds);
// VESPH_FUZZ_ITERATIONS=N runs N instead, VESPH_FUZZ_SEED=S another seed.
#include <doctest/doctest.h>
#include <hdf5.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "vesph/core/neighbours.hpp"
#include "vesph/io/config.hpp"
#include "vesph/io/output.hpp"
#include "vesph/physics/registry.hpp"

using namespace vesph;

namespace {

std::string repeatJoined(const std::string& part, const std::string& sep, std::size_t count) {
  std::string s;
  for (std::size_t k = 0; k < count; ++k) s += (k ? sep : "") + part;
  return s;
}

std::string readText(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::size_t envCount(const char* name, std::size_t def) {
  const char* v = std::getenv(name);
  return v ? static_cast<std::size_t>(std::strtoull(v, nullptr, 10)) : def;
}

std::string inputErrorOf(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("robustness: deep dotted keys, table headers and nested values are refused before parsing") {
  // toml++ 3.3 recurses per key part: 31000 parts overflowed the stack (SIGSEGV).
  const std::string deep_key = repeatJoined("a", ".", 31000) + " = 1\n";
  CHECK(inputErrorOf([&] { Config::fromString(deep_key, "deep.toml"); }).find("deep.toml: a key of 31000 dotted parts") !=
        std::string::npos);
  const std::string deep_header = "[" + repeatJoined("t", ".", 31000) + "]\nx = 1\n";
  CHECK(inputErrorOf([&] { Config::fromString(deep_header, "hdr.toml"); }).find("hdr.toml: a key of 31000") !=
        std::string::npos);
  const std::string deep_inline = "v = " + repeatJoined("{a = ", "", 40) + "1" + std::string(40, '}') + "\n";
  CHECK(inputErrorOf([&] { Config::fromString(deep_inline, "in.toml"); }).find("nested more than 16") != std::string::npos);
  // Dots inside strings, comments and values are no key parts; 16 parts are accepted.
  const std::string fine = "name = \"a.b.c.d.e.f.g.h.i.j.k.l.m.n.o.p.q.r\" # x.x.x.x.x.x.x.x.x.x.x.x.x.x.x.x.x.x\n"
                           "v = [1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5, 8.5, 9.5, 1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5, 8.5]\n"
                           "s = '''\n[x.x.x.x.x.x.x.x.x.x.x.x.x.x.x.x.x.x]\n'''\n" +
                           repeatJoined("k", ".", 16) + " = 1\n[" + repeatJoined("h", ".", 16) + "]\n";
  CHECK_NOTHROW(Config::fromString(fine, "fine.toml"));
  CHECK_THROWS_AS(Config::fromString(repeatJoined("k", ".", 17) + " = 1\n", "x.toml"), InputError);
  // Through --set as well (key and value).
  CHECK(inputErrorOf([&] { Config::fromString("", "s.toml", {repeatJoined("a", ".", 31000) + "=1"}); })
            .find("more than 16 key parts") != std::string::npos);
  CHECK_THROWS_AS(Config::fromString("", "s.toml", {"x=" + repeatJoined("[", "", 31000)}), InputError);
}

TEST_CASE("robustness: scene files over 4 MiB, directories and devices are refused naming the file") {
  const std::string big = "name = \"x\"\n# " + std::string(kMaxSceneBytes, 'x') + "\n";
  CHECK(inputErrorOf([&] { Config::fromString(big, "big.toml"); }).find("big.toml: ") == 0);
  const auto dir = std::filesystem::temp_directory_path() / "vesph_robustness_dir";
  std::filesystem::create_directories(dir);
  CHECK(inputErrorOf([&] { Config::fromFile(dir.string()); }).find("is a directory, not a scene file") != std::string::npos);
  CHECK(inputErrorOf([&] { Config::fromFile("/dev/null"); }) == "/dev/null: is a device, not a scene file");
  CHECK(inputErrorOf([&] { Config::fromFile("/dev/zero"); }) == "/dev/zero: is a device, not a scene file");
  std::ofstream((dir / "empty.toml").string()).flush();
  CHECK(inputErrorOf([&] { Config::fromFile((dir / "empty.toml").string()); }).find("the scene file is empty") !=
        std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_CASE("robustness: malformed --set array indices name the key") {
  const std::string scene = "[[blocks]]\nmin = 1\n";
  for (const std::string bad : {"blocks[abc].min=1", "blocks[].min=1", "blocks[[0]].min=1", "blocks[99999999999].min=1",
                                "blocks[5].min=1", "blocks]0[.min=1", "blocks[0.min=1", "blocks[-1].min=1"}) {
    CAPTURE(bad);
    const std::string msg = inputErrorOf([&] { Config::fromString(scene, "s.toml", {bad}); });
    CHECK(msg.find("--set '" + bad + "'") == 0);
  }
  CHECK_NOTHROW(Config::fromString(scene, "s.toml", {"blocks[0].min=2"}));
}

TEST_CASE("robustness: long values are echoed cut") {
  const std::string huge(2'000'000, 'w');
  Config cfg = Config::fromString("[fluid]\ndensity = \"" + huge + "\"\n", "long.toml");
  ConfigTable fluid = cfg.root().table("fluid");
  const std::string msg = inputErrorOf([&] { fluid.number("density", std::nullopt, Bound::positive); });
  CHECK(msg.find("long.toml: fluid.density: expected a positive number, got \"www") == 0);
  CHECK(msg.size() < 300);
  CHECK(msg.find("2000002 characters") != std::string::npos);
  const std::string set_msg = inputErrorOf([&] { Config::fromString("", "s.toml", {huge}); });
  CHECK(set_msg.size() < 300);
}

TEST_CASE("robustness: two constitutive models in one scene are refused, naming both") {
  const std::vector<std::pair<std::string, std::string>> pairs = {
      {"oldroyd_b", "ucm"}, {"oldroyd_b", "xpp"}, {"ucm", "second_order_fluid"}, {"xpp", "second_order_fluid"}};
  for (const auto& [a, b] : pairs) {
    CAPTURE(a);
    CAPTURE(b);
    Config cfg = Config::fromString("[effects." + a + "]\n[effects." + b + "]\n", "two.toml");
    ConfigTable eff = cfg.root().table("effects");
    const std::string msg = inputErrorOf([&] { makeEffects<2>(eff); });
    CHECK(msg.find("one constitutive model per scene") != std::string::npos);
    CHECK(msg.find("[effects." + a + "]") != std::string::npos);
    CHECK(msg.find("[effects." + b + "]") != std::string::npos);
  }
}

TEST_CASE("robustness: absurd stabiliser coefficients are refused with their range") {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"[effects.particle_shifting]\nspeed = 1e300\n", "effects.particle_shifting.speed: expected a positive number of at most 10000"},
      {"[effects.artificial_viscosity]\nalpha = 1e308\n", "effects.artificial_viscosity.alpha: expected a non-negative number of at most 100"},
      {"[effects.artificial_viscosity]\nbeta = 1e308\n", "effects.artificial_viscosity.beta: expected a non-negative number of at most 100"},
      {"[effects.density_diffusion]\ndelta = 1e308\n", "effects.density_diffusion.delta: expected a non-negative number of at most 10"}};
  for (const auto& [toml, expected] : cases) {
    CAPTURE(toml);
    Config cfg = Config::fromString(toml, "abs.toml");
    ConfigTable eff = cfg.root().table("effects");
    CHECK(inputErrorOf([&] { makeEffects<2>(eff); }).find(expected) != std::string::npos);
  }
}

TEST_CASE("robustness: the cell grid grows with the particles, not the domain") {
  // A 1e4 m square around a few hundred particles 1 mm apart: a grid over the whole domain would
  // need 2.5e13 cells. The lists must equal the brute force.
  Domain<2> dom;
  dom.lo = Vec<2>(-5e3, -5e3);
  dom.hi = Vec<2>(5e3, 5e3);
  ParticleSet<2> p;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 0.02);
  const std::size_t n = 400;
  for (std::size_t i = 0; i < n; ++i)
    p.add(Vec<2>(1.0 + u(rng), 2.0 + u(rng)), Vec<2>::Zero(), 1000, 1, ParticleKind::fluid, i);
  p.n_moving = n;
  NeighbourList<2> list;
  list.configure(dom, 2e-3, 2e-4);
  REQUIRE_NOTHROW(list.update(p, true));
  const double reach2 = 2.2e-3 * 2.2e-3;
  for (std::size_t i = 0; i < n; ++i) {
    std::set<Index> expected, got(list.nbr.begin() + list.start[i], list.nbr.begin() + list.start[i + 1]);
    for (std::size_t j = 0; j < n; ++j)
      if (j != i && (p.x(i) - p.x(j)).squaredNorm() < reach2) expected.insert(static_cast<Index>(j));
    CHECK(got == expected);
  }
  // Two particles 9 km apart along both axes: no grid over their extent is affordable, and the
  // refusal says how much it would take.
  ParticleSet<2> far;
  far.add(Vec<2>(-4.5e3, -4.5e3), Vec<2>::Zero(), 1000, 1, ParticleKind::fluid, 0);
  far.add(Vec<2>(4.5e3, 4.5e3), Vec<2>::Zero(), 1000, 1, ParticleKind::fluid, 1);
  far.n_moving = 2;
  try {
    list.update(far, true);
    FAIL("expected a refusal");
  } catch (const NumericalFailure& e) {
    CHECK(std::string(e.what()).find("GiB") != std::string::npos);
  }
}

// ---------------------------------------------------------------------------------------------
// Checkpoints

namespace {

// A file with one frame and its checkpoint, as a run writes them.
std::string writeSmallOutput(const std::filesystem::path& dir) {
  std::filesystem::remove_all(dir);
  ParticleSet<2> p;
  for (int i = 0; i < 5; ++i) p.add(Vec<2>(0.1 * i, 0.2), Vec<2>::Zero(), 1000, 1e-3, ParticleKind::fluid, i);
  p.n_moving = 5;
  FileAttributes attrs{2, "name = \"small\"\n", 0.1, 0.16, "quintic", {}};
  {
    OutputWriter<2> w(dir.string(), "small", attrs);
    w.writeFrame(0.0, 0, p, {DiagnosticsRow{0, 0, 0, 0, 0, 0}});
    Checkpoint c;
    c.state.assign(25, 0.5);
    c.id = {0, 1, 2, 3, 4};
    c.arrays.emplace_back("integrator.carried", std::vector<double>(10, 1.0));
    w.writeCheckpoint(c);
  }
  return (dir / "small.h5").string();
}

// Replaces /checkpoint/<name> by a dataset of the given rank (each extent `extent`) and type.
void replaceDataset(const std::string& file, const std::string& path, int rank, hsize_t extent, hid_t type) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  REQUIRE(f >= 0);
  H5Ldelete(f, path.c_str(), H5P_DEFAULT);
  hsize_t dims[3] = {extent, extent, extent};
  const hid_t space = H5Screate_simple(rank, dims, nullptr);
  const hid_t d = H5Dcreate2(f, path.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  H5Dclose(d);
  H5Sclose(space);
  H5Fclose(f);
}

// Replaces attribute `name` of object `path` by one of `count` elements (0: scalar) and type.
void replaceAttribute(const std::string& file, const std::string& path, const char* name, hsize_t count, hid_t type) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  REQUIRE(f >= 0);
  const hid_t o = H5Oopen(f, path.c_str(), H5P_DEFAULT);
  if (H5Aexists(o, name) > 0) H5Adelete(o, name);
  const hid_t space = count ? H5Screate_simple(1, &count, nullptr) : H5Screate(H5S_SCALAR);
  const hid_t a = H5Acreate2(o, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  std::vector<double> zeros(std::max<hsize_t>(count, 1) * 8, 0.0);
  H5Awrite(a, type, zeros.data());
  H5Aclose(a);
  H5Sclose(space);
  H5Oclose(o);
  H5Fclose(f);
}

}  // namespace

TEST_CASE("robustness: malformed checkpoints are refused naming the file and the dataset") {
  const auto dir = std::filesystem::temp_directory_path() / "vesph_robustness_ckpt";
  struct Damage {
    std::string what, expected;
    std::function<void(const std::string&)> apply;
  };
  const std::vector<Damage> damages = {
      {"state 2-D", "/checkpoint/state: expected a dataset of rank 1",
       [](const std::string& f) { replaceDataset(f, "/checkpoint/state", 2, 7, H5T_NATIVE_DOUBLE); }},
      {"state 3-D", "/checkpoint/state: expected a dataset of rank 1",
       [](const std::string& f) { replaceDataset(f, "/checkpoint/state", 3, 7, H5T_NATIVE_DOUBLE); }},
      {"id as strings", "/checkpoint/id: expected integer values",
       [](const std::string& f) { replaceDataset(f, "/checkpoint/id", 1, 5, H5T_C_S1); }},
      {"array 2-D", "/checkpoint/arrays/integrator.carried: expected a dataset of rank 1",
       [](const std::string& f) { replaceDataset(f, "/checkpoint/arrays/integrator.carried", 2, 4, H5T_NATIVE_DOUBLE); }},
      {"time of 2 elements", "/checkpoint/time: expected a single floating-point value",
       [](const std::string& f) { replaceAttribute(f, "/checkpoint", "time", 2, H5T_NATIVE_DOUBLE); }},
      {"step as double", "/checkpoint/step: expected a single integer value",
       [](const std::string& f) { replaceAttribute(f, "/checkpoint", "step", 0, H5T_NATIVE_DOUBLE); }},
      {"time missing", "/checkpoint/time: missing attribute",
       [](const std::string& f) {
         const hid_t h = H5Fopen(f.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
         H5Adelete_by_name(h, "/checkpoint", "time", H5P_DEFAULT);
         H5Fclose(h);
       }},
      {"scene of 2 strings", "/scene: expected a single string",
       [](const std::string& f) {
         const hid_t t = H5Tcopy(H5T_C_S1);
         H5Tset_size(t, 4);
         replaceAttribute(f, "/", "scene", 2, t);
         H5Tclose(t);
       }},
  };
  for (const Damage& d : damages) {
    CAPTURE(d.what);
    const std::string file = writeSmallOutput(dir);
    CHECK_NOTHROW(readResumeSource(dir.string(), "small"));
    d.apply(file);
    const std::string msg = inputErrorOf([&] { readResumeSource(dir.string(), "small"); });
    CHECK(msg.find("--resume: " + file + ": " + d.expected) == 0);
  }
  std::filesystem::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Fuzz targets

TEST_CASE("fuzz: mutated scene files parse or fail with an InputError") {
  std::vector<std::string> scenes;
  for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(VESPH_SOURCE_DIR) / "cases"))
    if (e.path().extension() == ".toml") scenes.push_back(readText(e.path()));
  std::sort(scenes.begin(), scenes.end());
  REQUIRE(!scenes.empty());
  const std::size_t iterations = envCount("VESPH_FUZZ_ITERATIONS", 3000);
  std::mt19937_64 rng(envCount("VESPH_FUZZ_SEED", 37));
  const std::string alphabet = "[]{}.=\"'#,\n \\-+0123456789eE.abc_xyz\t\r";
  auto pick = [&](std::size_t n) { return static_cast<std::size_t>(rng() % std::max<std::size_t>(n, 1)); };
  std::size_t parsed = 0, refused = 0;
  for (std::size_t it = 0; it < iterations; ++it) {
    std::string s = scenes[pick(scenes.size())];
    const std::size_t edits = 1 + pick(8);
    for (std::size_t e = 0; e < edits && !s.empty(); ++e) {
      const std::size_t at = pick(s.size());
      switch (pick(7)) {
        case 0: s[at] = alphabet[pick(alphabet.size())]; break;                     // replace a byte
        case 1: s.insert(at, 1, alphabet[pick(alphabet.size())]); break;            // insert a byte
        case 2: s.erase(at, 1 + pick(40)); break;                                   // delete a run
        case 3: s.insert(at, s.substr(pick(s.size()), 1 + pick(200))); break;       // duplicate a run
        case 4: s[at] = static_cast<char>(rng()); break;                            // any byte
        case 5: s.insert(at, std::string(1 + pick(300), alphabet[pick(6)])); break; // a run of brackets/dots
        default: s.insert(at, repeatJoined("k", ".", 1 + pick(40))); break;         // a dotted key
      }
    }
    std::vector<std::string> sets;
    if (pick(4) == 0) sets.push_back(std::string("blocks[") + std::to_string(pick(4)) + "].min=" + s.substr(pick(s.size()), pick(30)));
    try {
      Config cfg = Config::fromString(s, "fuzz.toml", sets);
      // What a scene's reading does first and last: the header keys and the resolved text.
      ConfigTable root = cfg.root();
      if (root.has("name")) root.string("name", std::nullopt);
      const std::string resolved = cfg.resolvedToml();
      CHECK(firstSceneDifference(resolved, resolved, {}).empty());
      ++parsed;
    } catch (const InputError&) {
      ++refused;
    }
  }
  MESSAGE(parsed << " mutated scenes parsed, " << refused << " refused with an InputError");
  CHECK(parsed + refused == iterations);
}

TEST_CASE("fuzz: damaged checkpoints resume or fail with an InputError") {
  const auto dir = std::filesystem::temp_directory_path() / "vesph_fuzz_ckpt";
  const std::size_t iterations = envCount("VESPH_FUZZ_ITERATIONS", 3000) / 15;
  std::mt19937_64 rng(envCount("VESPH_FUZZ_SEED", 37));
  auto pick = [&](std::size_t n) { return static_cast<std::size_t>(rng() % n); };
  const std::vector<std::string> datasets = {"/checkpoint/state", "/checkpoint/id", "/checkpoint/arrays/integrator.carried"};
  const std::vector<const char*> attrs = {"time", "step", "rhs_evals", "rejected_steps", "neighbour_builds",
                                          "wall_seconds", "max_density_deviation", "resumes"};
  const std::vector<hid_t> types = {H5T_NATIVE_DOUBLE, H5T_NATIVE_INT64, H5T_NATIVE_UINT8, H5T_NATIVE_FLOAT};
  std::size_t read = 0, refused = 0;
  for (std::size_t it = 0; it < iterations; ++it) {
    const std::string file = writeSmallOutput(dir);
    for (std::size_t e = 0, n = 1 + pick(3); e < n; ++e) {
      if (pick(2)) replaceDataset(file, datasets[pick(datasets.size())], 1 + static_cast<int>(pick(3)), pick(12), types[pick(types.size())]);
      else replaceAttribute(file, "/checkpoint", attrs[pick(attrs.size())], pick(3), types[pick(types.size())]);
    }
    try {
      readResumeSource(dir.string(), "small");
      ++read;
    } catch (const InputError&) {
      ++refused;
    }
  }
  MESSAGE(read << " damaged checkpoints read, " << refused << " refused with an InputError");
  CHECK(read + refused == iterations);
  std::filesystem::remove_all(dir);
}
