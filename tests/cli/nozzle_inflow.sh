# A circular nozzle (3D [inflow] with radius; cases/pipe_inflow_3d.toml: R = 8 dx, a parabolic
# profile of mean U = 0.01 m/s into a pipe at rest), run to t = 0.13 s:
#   - the buffer lies within the nozzle's radius, and its rings carry exactly rho U pi R^2
#     (sum over one station of m_k u_k / dx, to 1e-12);
#   - the release accounting is exact: a ring lane whose lead particle sits dx/2 behind the inlet
#     and moves at u releases floor(u t / dx - 1/2) + 1 particles by t; their number is the
#     summary's `released`, and the released particles carry the rings' masses (the fluid's mass
#     grew by sum_k m_k N_k, to 1e-12).
. "$(dirname "$0")/lib.sh"
CASE=$SRC/cases/pipe_inflow_3d.toml
expect 0 "ok: finished" -- "$VESPH" run "$CASE" -o "$WORK/run" --quiet --set time.end=0.13 --set output.interval=0.13
$PY - "$WORK/run" >"$WORK/check.log" 2>&1 <<'PYEOF' && pass || fail "nozzle accounting: $(tail -5 "$WORK/check.log")"
import json, math, sys
import h5py, numpy as np
run = sys.argv[1]
summary = json.load(open(f"{run}/summary.json"))
with h5py.File(f"{run}/pipe_inflow_3d.h5", "r") as f:
    frames = sorted(f["frames"], key=lambda g: f["frames"][g].attrs["time"])
    first, last = f["frames"][frames[0]], f["frames"][frames[-1]]
    t = last.attrs["time"]
    assert first.attrs["time"] == 0.0 and abs(t - 0.13) < 1e-12, (first.attrs["time"], t)
    kind, x, v, m, ids = (first[k][:] for k in ("kind", "position", "velocity", "mass", "id"))
rho0, U, R, dx = 1000.0, 0.01, 4.0e-3, 5.0e-4
buf = kind == 3
r = np.hypot(x[buf, 1], x[buf, 2])
assert r.max() <= R, r.max()
lead = buf & (np.abs(x[:, 0] - x[buf, 0].max()) < 1e-12)
assert abs(x[lead, 0][0] + 0.5 * dx) < 1e-12, x[lead, 0][0]
flux = np.sum(m[lead] * v[lead, 0]) / dx
print(f"buffer: {buf.sum()} particles, {lead.sum()} lanes; flow rate {flux:.12e} kg/s against rho U pi R^2 = {rho0 * U * math.pi * R * R:.12e}")
assert abs(flux / (rho0 * U * math.pi * R * R) - 1) < 1e-12
s = v[lead, 0] * t / dx - 0.5
assert np.all(np.abs(s - np.round(s)) > 1e-6), "a lane releases at t itself: choose another end time"
n = np.where(s >= 0, np.floor(s) + 1, 0)
expected, expected_mass = int(n.sum()), float(np.sum(n * m[lead]))
released = summary["flow"]["released"]
print(f"released {released}, expected {expected}")
assert released == expected, (released, expected)
with h5py.File(f"{run}/pipe_inflow_3d.h5", "r") as f:
    last = f["frames"][frames[-1]]
    new = (last["kind"][:] == 0) & ~np.isin(last["id"][:], ids)
    mass = float(last["mass"][:][new].sum())
print(f"released mass {mass:.12e} kg against {expected_mass:.12e}")
assert new.sum() == expected and abs(mass / expected_mass - 1) < 1e-12
PYEOF
cat "$WORK/check.log"
# radius: 3D only, a prescribed velocity, a circle inside the box
expect 2 "radius: .*at least one particle spacing" -- "$VESPH" check "$CASE" --set inflow.radius=1e-4
expect 2 "radius: .*inside the buffer box" -- "$VESPH" check "$CASE" --set inflow.radius=5e-3
expect 2 "profile_axis: .*absent with radius" -- "$VESPH" check "$CASE" --set inflow.profile_axis=1
finish
