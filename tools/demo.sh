#!/bin/sh
# The main demo: installs what is missing (Debian 12, as root), builds vesph, runs the
# transient Poiseuille case (cases/poiseuille_newtonian.toml) and compares it with the
# analytic solution, drawing the profiles (PNG).
set -eu
cd "$(dirname "$0")/.."
sh tools/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build --target vesph
./build/vesph run cases/poiseuille_newtonian.toml -o output/poiseuille_newtonian
/usr/bin/python3 tools/poiseuille_check.py output/poiseuille_newtonian/poiseuille_newtonian.h5 \
  --png output/poiseuille_newtonian/profiles.png --csv output/poiseuille_newtonian/errors.csv
echo "demo: output in $(pwd)/output/poiseuille_newtonian/ (open poiseuille_newtonian.xdmf in ParaView; profiles.png: simulated against analytic velocity profiles)"
