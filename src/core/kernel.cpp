#include "vesph/core/kernel.hpp"

#include <cmath>

#include "vesph/core/types.hpp"

namespace vesph {

std::string_view kernelName(KernelType t) {
  switch (t) {
    case KernelType::cubic: return "cubic";
    case KernelType::quintic: return "quintic";
    case KernelType::wendland_c2: return "wendland_c2";
  }
  return "?";
}

std::vector<std::string> kernelNames() { return {"cubic", "quintic", "wendland_c2"}; }

KernelType kernelFromName(std::string_view name) {
  if (name == "cubic") return KernelType::cubic;
  if (name == "quintic") return KernelType::quintic;
  if (name == "wendland_c2") return KernelType::wendland_c2;
  throw InputError("unknown kernel '" + std::string(name) +
                   "'; expected one of: cubic, quintic, wendland_c2");
}

Kernel::Kernel(KernelType type_, int dim_, double h_) : type(type_), dim(dim_), h(h_) {
  if (!(h > 0.0)) throw InputError("smoothing length must be positive");
  if (dim < 2 || dim > 3) throw InputError("kernel dimension must be 2 or 3");
  visit([&](auto shape) {
    using S = decltype(shape);
    support_q = S::support_q;
    w_scale = S::sigma(dim) / std::pow(h, dim);
    dw_scale = S::sigma(dim) / std::pow(h, dim + 1);
  });
}

double Kernel::W(double r) const {
  return visit([&](auto shape) { return w_scale * shape.f(r / h); });
}

double Kernel::dWdr(double r) const {
  return visit([&](auto shape) { return dw_scale * shape.df(r / h); });
}

double Kernel::latticeSum(double dx) const {
  const double support = supportRadius();
  const int reach = static_cast<int>(std::ceil(support / dx));
  const int kz = dim == 3 ? reach : 0;
  double n = 0;
  for (int i = -reach; i <= reach; ++i)
    for (int j = -reach; j <= reach; ++j)
      for (int k = -kz; k <= kz; ++k) {
        const double r = dx * std::sqrt(static_cast<double>(i * i + j * j + k * k));
        if (r < support) n += W(r);
      }
  return n;
}

}  // namespace vesph
