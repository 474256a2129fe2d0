// Verlet cell lists (vesph/core/neighbours.hpp) against an O(N^2) brute force with the
// minimum image: exact neighbour sets, the moving/fixed layout, the skin guarantee between
// rebuilds, and the rebuild trigger. All comparisons are exact (set equality): the list and
// the brute force evaluate the same r^2 < (cutoff + skin)^2 on the same doubles, and random
// positions never land on the boundary of the test to within rounding.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "vesph/core/domain.hpp"
#include "vesph/core/neighbours.hpp"
#include "vesph/core/particles.hpp"

using namespace vesph;

namespace {

template <int D>
Domain<D> makeDomain(const Vec<D>& lo, const Vec<D>& hi, std::array<bool, D> periodic) {
  Domain<D> d;
  d.lo = lo;
  d.hi = hi;
  d.periodic = periodic;
  return d;
}

// n_moving fluid particles, then n_fixed wall particles, uniformly random in the box (the
// particle set holds periodic coordinates wrapped into [lo, hi)). `outside` > 0 spreads the
// fixed particles that far beyond the box along non-periodic axes (walls and dummy layers
// sit there).
template <int D>
ParticleSet<D> randomParticles(const Domain<D>& dom, std::size_t n_moving, std::size_t n_fixed,
                               std::mt19937_64& rng, double outside = 0.0) {
  ParticleSet<D> p;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::size_t k = 0; k < n_moving + n_fixed; ++k) {
    const bool fixed = k >= n_moving;
    Vec<D> x;
    for (int a = 0; a < D; ++a) {
      const double ext = (fixed && !dom.periodic[a]) ? outside : 0.0;
      x[a] = dom.wrap(a, dom.lo[a] - ext + u(rng) * (dom.length(a) + 2 * ext));
    }
    p.add(x, Vec<D>::Zero(), 1000.0, 1.0, fixed ? ParticleKind::wall : ParticleKind::fluid, k);
  }
  return p;
}

template <int D>
double distance(const Domain<D>& dom, const ParticleSet<D>& p, std::size_t i, std::size_t j) {
  double r2 = 0;
  for (int a = 0; a < D; ++a) {
    const double d = dom.image(a, p.position[D * i + a] - p.position[D * j + a]);
    r2 += d * d;
  }
  return std::sqrt(r2);
}

// Brute force: the neighbours of i closer than reach (moving ones, fixed ones), where fixed
// particles only get moving neighbours.
template <int D>
void bruteForce(const Domain<D>& dom, const ParticleSet<D>& p, std::size_t i, double reach,
                std::set<Index>& moving, std::set<Index>& fixed) {
  moving.clear();
  fixed.clear();
  const double reach2 = reach * reach;
  for (std::size_t j = 0; j < p.size(); ++j) {
    if (j == i) continue;
    double r2 = 0;
    for (int a = 0; a < D; ++a) {
      const double d = dom.image(a, p.position[D * i + a] - p.position[D * j + a]);
      r2 += d * d;
    }
    if (!(r2 < reach2)) continue;
    if (j < p.n_moving) moving.insert(static_cast<Index>(j));
    else if (i < p.n_moving) fixed.insert(static_cast<Index>(j));
  }
}

// The list must hold exactly the brute-force sets, in the documented layout, once each.
template <int D>
void checkExact(const Domain<D>& dom, const ParticleSet<D>& p, const NeighbourList<D>& list) {
  const std::size_t N = p.size();
  REQUIRE(list.start.size() == N + 1);
  REQUIRE(list.split.size() == N);
  REQUIRE(list.start[0] == 0);
  REQUIRE(list.start[N] == list.nbr.size());
  const double reach = list.cutoff() + list.skin();
  std::set<Index> bm, bf;
  std::size_t max_count = 0, mismatches = 0;
  for (std::size_t i = 0; i < N; ++i) {
    REQUIRE(list.start[i] <= list.split[i]);
    REQUIRE(list.split[i] <= list.start[i + 1]);
    const std::vector<Index> lm(list.nbr.begin() + list.start[i], list.nbr.begin() + list.split[i]);
    const std::vector<Index> lf(list.nbr.begin() + list.split[i], list.nbr.begin() + list.start[i + 1]);
    const std::set<Index> sm(lm.begin(), lm.end()), sf(lf.begin(), lf.end());
    bruteForce(dom, p, i, reach, bm, bf);
    // No duplicates, right kinds, exact sets.
    const bool ok = sm.size() == lm.size() && sf.size() == lf.size() && sm == bm && sf == bf;
    if (!ok) {
      ++mismatches;
      if (mismatches <= 5) {
        CAPTURE(i);
        CAPTURE(i < p.n_moving);
        CHECK(lm.size() == sm.size());
        CHECK(lf.size() == sf.size());
        CHECK(sm == bm);
        CHECK(sf == bf);
      }
    }
    if (i >= p.n_moving) CHECK(lf.empty());  // fixed particles list only moving neighbours
    max_count = std::max(max_count, lm.size() + lf.size());
  }
  CHECK(mismatches == 0);
  CHECK(list.maxCount() == max_count);
}

// Every pair closer than the cutoff in the current configuration is in the list (both
// directions for moving pairs, moving j of fixed i).
template <int D>
void checkCoversCutoff(const Domain<D>& dom, const ParticleSet<D>& p, const NeighbourList<D>& list) {
  const std::size_t N = p.size();
  std::size_t missed = 0, close_pairs = 0;
  for (std::size_t i = 0; i < N; ++i) {
    const std::set<Index> row(list.nbr.begin() + list.start[i], list.nbr.begin() + list.start[i + 1]);
    for (std::size_t j = 0; j < N; ++j) {
      if (j == i || (i >= p.n_moving && j >= p.n_moving)) continue;
      if (distance(dom, p, i, j) < list.cutoff()) {
        ++close_pairs;
        if (!row.count(static_cast<Index>(j))) ++missed;
      }
    }
  }
  CHECK(close_pairs > 0);
  CHECK(missed == 0);
}

// Moves every moving particle by a random displacement of length below `max_step`, wrapping
// periodic coordinates as the particle set does.
template <int D>
void jiggle(const Domain<D>& dom, ParticleSet<D>& p, double max_step, std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::size_t i = 0; i < p.n_moving; ++i) {
    Vec<D> d;
    for (int a = 0; a < D; ++a) d[a] = g(rng);
    d *= max_step * u(rng) / d.norm();
    for (int a = 0; a < D; ++a) p.position[D * i + a] = dom.wrap(a, p.position[D * i + a] + d[a]);
  }
}

// The full scenario for one domain: exact lists, skin guarantee, rebuild trigger.
template <int D>
void scenario(const Domain<D>& dom, std::size_t n_moving, std::size_t n_fixed, double cutoff,
              double skin, std::uint64_t seed, double outside = 0.0) {
  std::mt19937_64 rng(seed);
  ParticleSet<D> p = randomParticles(dom, n_moving, n_fixed, rng, outside);
  NeighbourList<D> list;
  list.configure(dom, cutoff, skin);
  REQUIRE(list.update(p));  // first call always builds
  CHECK(list.builds() == 1);
  {
    INFO("fresh build");
    checkExact(dom, p, list);
  }

  // Displacements below skin/2: no rebuild, and no pair inside the cutoff is missing.
  jiggle(dom, p, 0.49 * skin, rng);
  CHECK_FALSE(list.update(p));
  CHECK(list.builds() == 1);
  {
    INFO("moved by < skin/2 without a rebuild");
    checkCoversCutoff(dom, p, list);
  }
  jiggle(dom, p, 0.49 * skin, rng);  // displacements from the build now reach up to 0.98 skin
  if (list.update(p)) {
    INFO("rebuilt after moving further");
    checkExact(dom, p, list);
  } else {
    INFO("still within skin/2 of the build");
    checkCoversCutoff(dom, p, list);
  }

  // One particle moving by more than skin/2 forces a rebuild, which is exact again.
  list.update(p, true);
  const std::size_t builds = list.builds();
  CHECK_FALSE(list.update(p));
  p.position[D * (n_moving / 2)] = dom.wrap(0, p.position[D * (n_moving / 2)] + 0.51 * skin);
  CHECK(list.update(p));
  CHECK(list.builds() == builds + 1);
  {
    INFO("rebuilt after one particle moved by 0.51 skin");
    checkExact(dom, p, list);
  }

  // A forced update rebuilds; a changed particle count rebuilds.
  CHECK(list.update(p, true));
  Vec<D> x = dom.lo + 0.5 * (dom.hi - dom.lo);
  p.add(x, Vec<D>::Zero(), 1000.0, 1.0, ParticleKind::wall, n_moving + n_fixed);
  CHECK(list.update(p));
  {
    INFO("rebuilt after adding a fixed particle");
    checkExact(dom, p, list);
  }
}

}  // namespace

TEST_CASE("neighbours: non-periodic 2D box matches brute force") {
  // 1.0 x 0.7 box, reach 0.1: ~44 particles per search disc on average.
  const Domain<2> dom = makeDomain<2>(Vec<2>(-0.2, 0.1), Vec<2>(0.8, 0.8), {false, false});
  scenario(dom, 1500, 500, 0.08, 0.02, 1);
}

TEST_CASE("neighbours: non-periodic 2D box with fixed particles outside it") {
  const Domain<2> dom = makeDomain<2>(Vec<2>(0.0, 0.0), Vec<2>(0.5, 1.2), {false, false});
  scenario(dom, 1000, 600, 0.05, 0.01, 2, 0.25);
}

TEST_CASE("neighbours: non-periodic 3D box matches brute force") {
  const Domain<3> dom =
      makeDomain<3>(Vec<3>(0.0, -0.5, 0.2), Vec<3>(1.0, 0.3, 0.9), {false, false, false});
  scenario(dom, 2500, 700, 0.12, 0.03, 3, 0.1);
}

TEST_CASE("neighbours: 2D box periodic along x") {
  const Domain<2> dom = makeDomain<2>(Vec<2>(-0.3, 0.1), Vec<2>(1.7, 1.3), {true, false});
  scenario(dom, 1800, 400, 0.12, 0.03, 4, 0.1);
}

TEST_CASE("neighbours: 2D box periodic along y") {
  const Domain<2> dom = makeDomain<2>(Vec<2>(0.0, 0.0), Vec<2>(1.0, 0.6), {false, true});
  scenario(dom, 1500, 300, 0.1, 0.02, 5, 0.1);
}

TEST_CASE("neighbours: 2D box periodic along both axes, lengths near 3 search radii") {
  // 3.3 and 4.1 search radii per period: 3 and 4 cells, where a cell's 3x3 block wraps onto
  // the far side of the box.
  const double reach = 0.1 + 0.025;
  const Domain<2> dom =
      makeDomain<2>(Vec<2>(0.0, 0.0), Vec<2>(3.3 * reach, 4.1 * reach), {true, true});
  scenario(dom, 400, 100, 0.1, 0.025, 6);
}

TEST_CASE("neighbours: 3D box periodic along x and z") {
  const Domain<3> dom =
      makeDomain<3>(Vec<3>(0.0, 0.0, 0.0), Vec<3>(0.8, 0.6, 0.7), {true, false, true});
  scenario(dom, 2500, 600, 0.11, 0.02, 7, 0.1);
}

TEST_CASE("neighbours: 3D box periodic along all axes") {
  const double reach = 0.1 + 0.02;
  const Domain<3> dom = makeDomain<3>(Vec<3>(-0.1, 0.0, 0.3),
                                      Vec<3>(-0.1 + 3.2 * reach, 0.6, 0.3 + 5.5 * reach),
                                      {true, true, true});
  scenario(dom, 2000, 500, 0.1, 0.02, 8);
}

TEST_CASE("neighbours: zero skin lists exactly the pairs inside the cutoff") {
  const Domain<2> dom = makeDomain<2>(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), {true, false});
  std::mt19937_64 rng(9);
  ParticleSet<2> p = randomParticles(dom, 800, 200, rng);
  NeighbourList<2> list;
  list.configure(dom, 0.09, 0.0);
  REQUIRE(list.update(p));
  checkExact(dom, p, list);
  // Without a skin any movement at all triggers a rebuild.
  p.position[0] = dom.wrap(0, p.position[0] + 1e-9);
  CHECK(list.update(p));
}

TEST_CASE("neighbours: a periodic axis shorter than 3 search radii is rejected") {
  const double cutoff = 0.1, skin = 0.02, reach = cutoff + skin;
  NeighbourList<2> list2;
  // Just below 3 (cutoff + skin) along a periodic axis: rejected.
  CHECK_THROWS_AS(list2.configure(makeDomain<2>(Vec<2>(0, 0), Vec<2>(2.99 * reach, 1.0), {true, false}),
                                  cutoff, skin),
                  InputError);
  CHECK_THROWS_AS(list2.configure(makeDomain<2>(Vec<2>(0, 0), Vec<2>(1.0, 2.5 * reach), {true, true}),
                                  cutoff, skin),
                  InputError);
  // The same short length along a non-periodic axis is fine, and so is 3.01 radii periodic.
  CHECK_NOTHROW(list2.configure(makeDomain<2>(Vec<2>(0, 0), Vec<2>(2.99 * reach, 1.0), {false, false}),
                                cutoff, skin));
  CHECK_NOTHROW(list2.configure(makeDomain<2>(Vec<2>(0, 0), Vec<2>(3.01 * reach, 1.0), {true, false}),
                                cutoff, skin));
  NeighbourList<3> list3;
  CHECK_THROWS_AS(
      list3.configure(makeDomain<3>(Vec<3>(0, 0, 0), Vec<3>(1.0, 1.0, 2.9 * reach), {false, false, true}),
                      cutoff, skin),
      InputError);
  CHECK_NOTHROW(
      list3.configure(makeDomain<3>(Vec<3>(0, 0, 0), Vec<3>(1.0, 1.0, 3.5 * reach), {false, false, true}),
                      cutoff, skin));
}
