# [checks] leave_domain: a fluid particle that leaves the domain stops the run ("stop", the
# default: exit 3) or is removed and counted ("remove": diagnostics `escaped`, summary.json
# `escaped`), and a run with removals resumes exactly (the count is in the checkpoint).
# The quarter-resolution Newtonian drop on a domain and wall cut to |x| <= 1.4 cm: its spreading
# sheet passes x = +-1.4 cm at t V/D = 1.6.
. "$(dirname "$0")/lib.sh"
DROP=$SRC/cases/drop_newtonian.toml
Q="--set particles.spacing=8e-4 --set domain.min=[-0.014,-0.0024] --set domain.max=[0.014,0.06] --set blocks[1].min=[-0.014,-0.0024] --set blocks[1].max=[0.014,0.0] --set output.interval=0.005"
# shellcheck disable=SC2086
expect 3 "diverged: fluid particle id [0-9]+ left the domain" -- "$VESPH" run "$DROP" -o "$WORK/stop" --quiet $Q --set time.end=0.04
# shellcheck disable=SC2086
expect 2 "leave_domain: expected one of" -- "$VESPH" check "$DROP" $Q --set checks.leave_domain=drop
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$DROP" -o "$WORK/rm" --quiet $Q --set time.end=0.04 --set checks.leave_domain=remove
$PY - "$WORK/rm" >"$WORK/rm.log" 2>&1 <<'PYEOF' && pass || fail "removal of escaped particles: $(tail -3 "$WORK/rm.log")"
import json, sys
import h5py, numpy as np
d = sys.argv[1]
s = json.load(open(d + "/summary.json"))
with h5py.File(d + "/drop_newtonian.h5", "r") as f:
    esc = f["diagnostics/escaped"][:]
    frames = sorted(f["frames"])
    n0 = int((f["frames"][frames[0]]["kind"][:] == 0).sum())
    n1 = int((f["frames"][frames[-1]]["kind"][:] == 0).sum())
    x = f["frames"][frames[-1]]["position"][:]
    m = f["frames"][frames[-1]]["kind"][:] == 0
assert s["escaped"] > 0, "nothing escaped: no test"
assert esc[-1] == s["escaped"] and np.all(np.diff(esc) >= 0), "escaped column"
assert n1 == n0 - s["escaped"] == s["fluid_particles"], (n0, n1, s["escaped"])
assert np.all(np.abs(x[m, 0]) <= 0.014), "a fluid particle outside the domain in the last frame"
print("escaped", s["escaped"], "of", n0)
PYEOF
# The stopped run goes on from its last good state with leave_domain switched to "remove"
# ([checks] may change on --resume; its checkpoint has no particle-set arrays, the set being
# the scene's own).
# shellcheck disable=SC2086
expect 0 "ok: finished" -- "$VESPH" run "$DROP" -o "$WORK/stop" --quiet $Q --set time.end=0.04 --set checks.leave_domain=remove --resume
grep -q '"escaped": [1-9]' "$WORK/stop/summary.json" && pass || fail "the resumed stopped run removed nothing: $(cat "$WORK/stop/summary.json")"
# Split at t = 0.02 s (before the first removal) and at 0.035 s (after some), both output
# times of the whole run (an extra output time would change the step sequence).
for split in 0.02 0.035; do
  # shellcheck disable=SC2086
  expect 0 "ok: finished" -- "$VESPH" run "$DROP" -o "$WORK/seg$split" --quiet $Q --set time.end=$split --set checks.leave_domain=remove
  # shellcheck disable=SC2086
  expect 0 "ok: finished" -- "$VESPH" run "$DROP" -o "$WORK/seg$split" --quiet $Q --set time.end=0.04 --set checks.leave_domain=remove --resume
  $PY - "$WORK/rm" "$WORK/seg$split" >"$WORK/seg.log" 2>&1 <<'PYEOF' && pass || fail "segmented run (split $split) differs: $(tail -3 "$WORK/seg.log")"
import sys
import h5py, numpy as np
a, b = (h5py.File(d + "/drop_newtonian.h5", "r") for d in sys.argv[1:3])
la, lb = a["frames"][sorted(a["frames"])[-1]], b["frames"][sorted(b["frames"])[-1]]
assert la.attrs["step"] == lb.attrs["step"] and np.array_equal(la["id"][:], lb["id"][:])
err = np.abs(la["velocity"][:] - lb["velocity"][:]).max() / np.abs(la["velocity"][:]).max()
assert err < 1e-12, err
assert a["diagnostics/escaped"][-1] == b["diagnostics/escaped"][-1]
print("same", err)
PYEOF
done
finish
