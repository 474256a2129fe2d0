#pragma once
// Smoothing kernels W(r, h) with their radial derivative dW/dr, normalised in 1D, 2D and 3D.
//   cubic spline   thesis eq. (3.3) (Fang eq. 22), support 2h
//   quintic spline thesis eq. (3.4) (Morris et al. 1997), support 3h
//   Wendland C2    Wendland (1995), Dehnen & Aly (2012) table 1, support 2h
// The kernel type is a runtime choice; hot loops dispatch once per pass through visit(),
// so the per-pair evaluation is inlined for the chosen kernel.
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

namespace vesph {

enum class KernelType { cubic, quintic, wendland_c2 };

std::string_view kernelName(KernelType t);
KernelType kernelFromName(std::string_view name);  // throws InputError listing valid names
std::vector<std::string> kernelNames();

// One kernel shape, evaluated through its dimensionless profile f(q), q = r/h:
// W(r,h) = sigma_D / h^D * f(q),  dW/dr = sigma_D / h^(D+1) * f'(q).
struct CubicSpline {
  static constexpr double support_q = 2.0;
  static double sigma(int dim) {  // thesis eq. (3.3): 1/h, 15/(7 pi h^2), 3/(2 pi h^3)
    return dim == 1 ? 1.0 : dim == 2 ? 15.0 / (7.0 * M_PI) : 3.0 / (2.0 * M_PI);
  }
  static double f(double q) {
    if (q < 1.0) return 2.0 / 3.0 - q * q + 0.5 * q * q * q;
    if (q < 2.0) { const double a = 2.0 - q; return a * a * a / 6.0; }
    return 0.0;
  }
  static double df(double q) {
    if (q < 1.0) return -2.0 * q + 1.5 * q * q;
    if (q < 2.0) { const double a = 2.0 - q; return -0.5 * a * a; }
    return 0.0;
  }
  static double df_over_q(double q) {  // f'(q)/q, finite at q -> 0
    if (q < 1.0) return -2.0 + 1.5 * q;
    return df(q) / q;
  }
};

struct QuinticSpline {
  static constexpr double support_q = 3.0;
  // Thesis eq. (3.4) in 2D. In 3D the exact normalisation of this profile is 1/(120 pi); the
  // 3/(359 pi) often quoted after Morris et al. (1997) is 0.28 % too large.
  static double sigma(int dim) {
    return dim == 1 ? 1.0 / 120.0 : dim == 2 ? 7.0 / (478.0 * M_PI) : 1.0 / (120.0 * M_PI);
  }
  static double f(double q) {
    if (q >= 3.0) return 0.0;
    const double a = 3.0 - q, b = 2.0 - q, c = 1.0 - q;
    double s = a * a * a * a * a;
    if (q < 2.0) s -= 6.0 * b * b * b * b * b;
    if (q < 1.0) s += 15.0 * c * c * c * c * c;
    return s;
  }
  static double df(double q) {
    if (q >= 3.0) return 0.0;
    const double a = 3.0 - q, b = 2.0 - q, c = 1.0 - q;
    double s = -5.0 * a * a * a * a;
    if (q < 2.0) s += 30.0 * b * b * b * b;
    if (q < 1.0) s -= 75.0 * c * c * c * c;
    return s;
  }
  static double df_over_q(double q) { return df(q) / q; }
};

struct WendlandC2 {
  static constexpr double support_q = 2.0;
  // W = sigma/h^D (1 - q/2)^4 (2q + 1) in 2D and 3D (the 1D Wendland C2 has another profile).
  static double sigma(int dim) {
    return dim == 1 ? 5.0 / 8.0 : dim == 2 ? 7.0 / (4.0 * M_PI) : 21.0 / (16.0 * M_PI);
  }
  static double f(double q) {
    if (q >= 2.0) return 0.0;
    const double a = 1.0 - 0.5 * q, a2 = a * a;
    return a2 * a2 * (2.0 * q + 1.0);
  }
  static double df(double q) {
    if (q >= 2.0) return 0.0;
    const double a = 1.0 - 0.5 * q;
    return -5.0 * q * a * a * a;
  }
  static double df_over_q(double q) {  // no division: the profile's derivative carries q
    if (q >= 2.0) return 0.0;
    const double a = 1.0 - 0.5 * q;
    return -5.0 * a * a * a;
  }
};

// A kernel at a fixed smoothing length h in dimension dim.
struct Kernel {
  KernelType type = KernelType::quintic;
  int dim = 2;
  double h = 1.0;

  Kernel() = default;
  Kernel(KernelType type_, int dim_, double h_);

  double supportRadius() const { return support_q * h; }
  // Sum of W over a full support of a square (cubic) lattice of spacing dx, the centre
  // included: the number density of an undisturbed interior particle, 1/m^dim.
  double latticeSum(double dx) const;
  double W(double r) const;
  double dWdr(double r) const;

  // Calls fn(Shape{}) with the kernel shape type, for dispatch outside hot loops.
  template <class Fn>
  decltype(auto) visit(Fn&& fn) const {
    switch (type) {
      case KernelType::cubic: return fn(CubicSpline{});
      case KernelType::quintic: return fn(QuinticSpline{});
      case KernelType::wendland_c2: break;
    }
    return fn(WendlandC2{});
  }

  double support_q = 3.0;
  double w_scale = 1.0;   // sigma / h^D
  double dw_scale = 1.0;  // sigma / h^(D+1)
};

}  // namespace vesph
