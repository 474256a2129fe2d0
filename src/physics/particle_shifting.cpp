// Particle shifting (Fickian), as a shifting velocity in the right-hand side.
//
// Lind et al. (2012, J. Comput. Phys. 231, 1499) move the particles after each step by
//   dr_i = -D grad C_i,  grad C_i = sum_j V_j [1 + R (W_ij / W(dx))^n] grad_i W_ij
// (the concentration gradient with their tensile-instability term, R = 0.2, n = 4), which pushes
// particles from crowded to sparse regions and keeps the particle distribution uniform; with
// the diffusion coefficient of Skillen et al. (2013, Comput. Methods Appl. Mech. Engrg. 265, 163),
// D = A h U dt, the shift per unit time is a velocity,
//   du_i = -A h U grad C_i,
// which this effect adds to dx_i/dt (as XSPH adds its correction), so that every integrator
// carries it with its own step and error control, and nothing changes the state between steps.
// A particle that moves with v_i + du_i instead of v_i sees its values change along the path;
// the fields are carried with it to first order (Lind et al.'s Taylor correction, here as rates):
//   dv_i/dt += (du_i . grad) v_i,   drho_i/dt += du_i . grad rho_i,
//   dS_i/dt += (du_i . grad) S_i   for every evolving field S (elastic stresses),
// with the gradients in the difference form sum_j V_j (phi_j - phi_i) grad_i W_ij (Lind et al.'s;
// for a linear field g.x it gives M_i g, M_i = -sum_j V_j F_ij r_ij r_ij^T, the identity on a full
// lattice support and within about 10 % of it on a lattice jittered by 0.15 dx). The
// renormalised gradient (M_i^-1 applied, exact for linear fields) was tried: the full-resolution
// Oldroyd-B ISPH drop then diverged at t V/D = 2.09 (near-singular M_i of particles beside the
// surface band amplify the correction), the plain form carries it through.
//
// Free surfaces: there the support is truncated and grad C points into the fluid for reasons
// that have nothing to do with disorder; a shift along it would pull the surface rows outward and
// spread the fluid (a falling drop's interior density fell by 1-5 % with shifting applied to the
// flagged particles only, docs/validation.md §11). As in delta+-SPH (Sun et al. 2017, J. Comput.
// Phys. 340, 439, §3) the particles of the surface band — those flagged by
// [effects.free_surface] and those with a flagged particle in their support — keep only the
// shift's tangential part: du_i -= (du_i . n_i) n_i, n_i = -grad C_i / |grad C_i|. Without
// [effects.free_surface] every particle is shifted in full (channels, closed boxes).
//
// Wall particles count in grad C (they occupy the space behind the wall, so the fluid is not
// pushed into it) and in the velocity gradient with the wall velocities the walls gave them;
// an evolving field enters with wall values only when the walls extrapolate it.
// V_j = m_j / rho_j.
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

// Scalar components of the evolving fields this effect carries (an elastic stress: 3 in 2-D,
// 6 in 3-D; two such fields fit).
constexpr int kMaxCarried = 12;

template <int D>
class ParticleShifting final : public PairEffect<D, ParticleShifting<D>> {
 public:
  explicit ParticleShifting(ConfigTable& cfg)
      : coefficient_(cfg.numberIn("coefficient", 2.0, 0.0, 100.0, "A of the shifting velocity -A h U grad C")),
        speed_(readSpeed(cfg)),
        tensile_(cfg.numberIn("tensile_correction", 0.2, 0.0, 10.0, "R of Lind et al.'s 1 + R (W/W(dx))^n")),
        exponent_(static_cast<int>(cfg.integer("exponent", 4, 1, 16))) {}
  std::string_view name() const override { return "particle_shifting"; }

  // U, a flow speed in m/s: 1e4 m/s is beyond any flow vesph resolves (an absurd U would drive
  // the shifting step limit to zero). The key is read without a unit label, so that the
  // missing-key message is the one it always was; the bound's message names the unit.
  static double readSpeed(ConfigTable& cfg) {
    constexpr double kMaxSpeed = 1e4;
    const double u = cfg.number("speed", std::nullopt, Bound::positive);
    if (u > kMaxSpeed) cfg.fail("speed", "a positive number of at most " + std::to_string(static_cast<long>(kMaxSpeed)) + " (m/s)");
    return u;
  }
  Phase phase() const override { return Phase::forces; }
  bool needsKernelValue() const override { return true; }
  // Set up after the other force effects; the evolving fields (registered by the rates phase,
  // which is set up before this one) are then all known.
  int passOrder() const override { return 10; }

  void setup(Setup<D>& s) override {
    w_dx_ = s.kernel.W(s.spacing);
    h_ = s.kernel.h;
    surface_ = s.find("free_surface") != nullptr ? &s.particles.fields.require("free_surface", 1) : nullptr;
    carried_.clear();
    int components = 0;
    for (std::size_t k = 0; k < s.evolving->size(); ++k) {
      const Field* f = (*s.evolving)[k];
      carried_.push_back({f, static_cast<int>(k), components, f->extrapolated_to_walls});
      components += f->components;
    }
    if (components > kMaxCarried)
      throw InputError("effects.particle_shifting: the scene's evolving fields have " + std::to_string(components) +
                       " components, more than the " + std::to_string(kMaxCarried) + " the shifting carries");
    carried_components_ = components;
  }

  struct Local {
    Vec<D> gradC;                       // sum_j V_j [1 + R (W/W(dx))^n] grad W
    Eigen::Matrix<double, D, D> gradV;  // (a, b): d v_a / d x_b
    Vec<D> gradRho;
    double gradS[kMaxCarried * D];      // component-major: [c * D + b]
    bool nearSurface;
    Vec<D> vi;
    double rhoi;
  };

  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& p = ctx.particles;
    Local l;
    l.gradC.setZero();
    l.gradV.setZero();
    l.gradRho.setZero();
    for (int k = 0; k < carried_components_ * D; ++k) l.gradS[k] = 0.0;
    l.nearSurface = surface_ && surface_->data[i] > 0.5;
    l.vi = p.v(i);
    l.rhoi = p.density[i];
    return l;
  }

  void pair(const RhsContext<D>& ctx, Index i, const Neighbour<D>& nb, Local& l) const {
    accumulate(ctx, i, nb, l, true);
  }
  void pairFixed(const RhsContext<D>& ctx, Index i, const Neighbour<D>& nb, Local& l) const {
    accumulate(ctx, i, nb, l, false);
  }

  void end(const RhsContext<D>& ctx, Index i, Local& l) const {
    Vec<D> du = -coefficient_ * h_ * speed_ * l.gradC;
    if (l.nearSurface) {
      const double g = l.gradC.norm();
      if (g > 0) {
        const Vec<D> n = -l.gradC / g;
        du -= du.dot(n) * n;
      }
    }
    for (int a = 0; a < D; ++a) ctx.dxdt[D * i + a] += du[a];
    const Vec<D> dv = l.gradV * du;
    for (int a = 0; a < D; ++a) ctx.dvdt[D * i + a] += dv[a];
    ctx.drhodt[i] += l.gradRho.dot(du);
    for (const Carried& cf : carried_) {
      const int nc = cf.field->components;
      double* rate = ctx.field_rates[cf.slot] + static_cast<std::size_t>(nc) * i;
      for (int c = 0; c < nc; ++c) {
        double s = 0;
        for (int b = 0; b < D; ++b) s += l.gradS[(cf.offset + c) * D + b] * du[b];
        rate[c] += s;
      }
    }
  }

 private:
  struct Carried {
    const Field* field;
    int slot;
    int offset;  // its first component in Local::gradS
    bool walls;  // the walls extrapolate it (Fang eq. 46)
  };

  void accumulate(const RhsContext<D>& ctx, Index i, const Neighbour<D>& nb, Local& l, bool moving) const {
    const ParticleSet<D>& p = ctx.particles;
    const Index j = nb.j;
    const double Vj = p.mass[j] / p.density[j];
    const Vec<D> gradW = nb.F * nb.rij;
    const double ratio = nb.W / w_dx_;
    double power = ratio;  // ratio^n by multiplication (n a small integer), not pow in the pair loop
    for (int k = 1; k < exponent_; ++k) power *= ratio;
    l.gradC += Vj * (1.0 + tensile_ * power) * gradW;
    const Vec<D> vj = p.v(j);
    l.gradV += (Vj * (vj - l.vi)) * gradW.transpose();
    l.gradRho += Vj * (p.density[j] - l.rhoi) * gradW;
    if (surface_ && surface_->data[j] > 0.5) l.nearSurface = true;
    for (const Carried& cf : carried_) {
      if (!moving && !cf.walls) continue;
      const double* sj = cf.field->at(j);
      const double* si = cf.field->at(i);
      for (int c = 0; c < cf.field->components; ++c) {
        const double d = Vj * (sj[c] - si[c]);
        for (int b = 0; b < D; ++b) l.gradS[(cf.offset + c) * D + b] += d * gradW[b];
      }
    }
  }

  double coefficient_, speed_, tensile_;
  int exponent_;
  double w_dx_ = 0, h_ = 0;
  const Field* surface_ = nullptr;
  std::vector<Carried> carried_;
  int carried_components_ = 0;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeParticleShifting, ParticleShifting)
}  // namespace vesph
