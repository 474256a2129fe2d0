"""The explicit stability limits of the time step (docs/theory.md §8; Fang et al. 2006 eqs.
51-53), with the default coefficients the C++ uses (include/vesph/time/integrator.hpp,
StepControl), read from `vesph list --json`:
    acoustic  cfl * h / (c + v_max)           (cfl: 0.125 WCSPH, 0.175 ISPH by default)
    viscous   viscous_coefficient * h^2 / nu
    force     force_coefficient * sqrt(h / a_max)
"""
import math

from vesph.catalogue import catalogue


def default_coefficients(scheme="wcsph", vesph=None):
    """{'cfl', 'viscous', 'force', 'relaxation'}: the defaults of the pressure scheme."""
    s = catalogue(vesph)["step_limits"]
    return {"cfl": float(s["cfl"][scheme]), "viscous": float(s["viscous_coefficient"]),
            "force": float(s["force_coefficient"]), "relaxation": float(s["relaxation_coefficient"])}


def step_limits(h, c, nu, vmax=0.0, amax=0.0, cfl=None, viscous=None, force=None, scheme="wcsph",
                vesph=None):
    """The limits, s, as a dict acoustic / viscous / force, with 'smallest' and 'controls' (the
    name of the smallest); a coefficient not given is the scheme's default."""
    d = default_coefficients(scheme, vesph)
    cfl = d["cfl"] if cfl is None else cfl
    viscous = d["viscous"] if viscous is None else viscous
    force = d["force"] if force is None else force
    out = {"acoustic": cfl * h / (c + vmax) if c + vmax > 0 else math.inf,
           "viscous": viscous * h * h / nu if nu > 0 else math.inf,
           "force": force * math.sqrt(h / amax) if amax > 0 else math.inf}
    out["smallest"] = min(out.values())
    out["controls"] = min(("acoustic", "viscous", "force"), key=lambda k: out[k])
    return out
