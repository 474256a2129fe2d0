# Shared helpers for the command-line tests; sourced by each test with $1 = vesph binary,
# $2 = source directory.
set -u
VESPH=$1
SRC=$2
SCENE=$SRC/cases/poiseuille_newtonian.toml
PY=/usr/bin/python3
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
FAILED=0
PASSED=0
fail() { echo "FAIL: $*"; FAILED=$((FAILED + 1)); }
pass() { PASSED=$((PASSED + 1)); }
# expect CODE PATTERN -- command...: runs the command, checks exit code and that its stderr
# (or stdout) matches PATTERN (grep -E).
expect() {
  code=$1; pattern=$2; shift 3
  "$@" >"$WORK/out" 2>"$WORK/err"
  got=$?
  if [ "$got" != "$code" ]; then
    fail "'$*' exited $got, expected $code; stderr: $(tail -c 400 "$WORK/err")"
  elif ! grep -Eq -- "$pattern" "$WORK/err" "$WORK/out"; then
    fail "'$*' output does not match /$pattern/; stderr: $(tail -c 400 "$WORK/err")"
  else
    pass
  fi
}
finish() {
  echo "$PASSED passed, $FAILED failed"
  [ "$FAILED" = 0 ]
}
