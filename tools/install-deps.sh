#!/bin/sh
# Installs the Debian 12 packages vesph needs to build, test and plot (run as root).
# Does nothing when everything is already installed.
set -eu
PACKAGES="build-essential cmake ninja-build pkg-config
  libsundials-dev libeigen3-dev libsuitesparse-dev libhdf5-dev libhdf5-openmpi-dev hdf5-tools
  doctest-dev libtomlplusplus-dev libcli11-dev nlohmann-json3-dev
  libhypre-dev libopenmpi-dev openmpi-bin libtrilinos-zoltan-dev
  python3 python3-numpy python3-scipy python3-h5py python3-matplotlib libxml2-utils"
missing=""
for p in $PACKAGES; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  echo "install-deps: installing:$missing"
  if [ "$(id -u)" != 0 ]; then
    echo "install-deps: root is needed to install packages (run as root or with sudo)" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  # shellcheck disable=SC2086
  apt-get install -y -qq --no-install-recommends $missing
fi
