# Long test (ctest -L long): the second-order fluid's H/20 channel start-up of
# tests/cli/second_order_fluid_validation.sh for the CEF form under the covariant, mixed and
# Jaumann derivatives (the suite runs the four derivatives with the Rivlin-Ericksen form and CEF
# with the contravariant one): profile, stresses and start-up history within 3 % (lib.sh:
# sof_form). About 40 s on one core.
. "$(dirname "$0")/../cli/lib.sh"
for d in covariant mixed jaumann; do sof_form cef "$d"; done
finish
