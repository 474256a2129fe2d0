#include "vesph/boundary/domain_exit.hpp"

#include <memory>

#include "vesph/boundary/registry.hpp"


namespace vesph {

template <int D>
void DomainExit<D>::apply(StepContext<D>& system, double, double, double* y) {
  remove_.clear();
  const std::size_t n = system.particles.ownedMoving();  // the state's particles
  for (std::size_t i = 0; i < n; ++i)
    if (!system.domain.insideNonPeriodic(y + D * i)) remove_.push_back(static_cast<Index>(i));
}

template <int D>
void DomainExit<D>::collectChanges(const StepContext<D>&, ParticleChanges& out) {
  out.remove.insert(out.remove.end(), remove_.begin(), remove_.end());
}

template <int D>
void DomainExit<D>::resized(StepContext<D>&, const ParticleRemap&) {
  escaped_ += remove_.size();
  remove_.clear();
}

template <int D>
void DomainExit<D>::diagnostics(std::vector<double>& values) const {
  // The row of a step counts that step's removals (made right after it).
  const double escaped = static_cast<double>(escaped_ + remove_.size());
  values.push_back(this->distribution() ? this->distribution()->sum(escaped) : escaped);  // every process's
}

template <int D>
void DomainExit<D>::summarize(nlohmann::json& summary) const {
  summary["escaped"] = this->distribution() ? this->distribution()->sum(escaped_) : escaped_;
}

template <int D>
std::string DomainExit<D>::describe() const {
  return "# leave_domain = \"remove\": fluid particles outside the domain are removed and counted (escaped)\n";
}

template <int D>
void DomainExit<D>::saveCarried(NamedArrays& out) const {
  // A run across processes: the whole run's count (collective), which process 0 takes back.
  const double escaped = static_cast<double>(escaped_);
  out.emplace_back("escaped", std::vector<double>{this->distribution() ? this->distribution()->sum(escaped) : escaped});
}

template <int D>
void DomainExit<D>::restoreCarried(const ArrayLookup& find) {
  // Absent in a checkpoint written while leave_domain was "stop" (nothing was removed then).
  const std::vector<double>* e = find("escaped");
  if (e && e->size() != 1) throw InputError("--resume: the checkpoint's count of escaped particles is malformed");
  const bool mine = !this->distribution() || this->distribution()->rank() == 0;  // counted once
  escaped_ = e && mine ? static_cast<std::uint64_t>((*e)[0]) : 0;
}

// What happens to a fluid particle that leaves the domain ([checks] leave_domain; registered in
// src/boundary/registry.cpp): the run stops (a numerical failure, the default) or the particle
// is removed and counted (splashes).
template <int D>
void buildDomainExit(BoundaryBuild<D>& b) {
  b.facts.removes_leaving = b.root.table("checks").choice("leave_domain", "stop", {"stop", "remove"}) == "remove";
  if (b.facts.removes_leaving) b.hooks.push_back(std::make_unique<DomainExit<D>>());
}

template void buildDomainExit<2>(BoundaryBuild<2>&);
template void buildDomainExit<3>(BoundaryBuild<3>&);

template class DomainExit<2>;
template class DomainExit<3>;

}  // namespace vesph
