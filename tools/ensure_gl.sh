#!/usr/bin/env bash
# Headless OpenGL for the reference renderer (shadowmath.render): EGL with Mesa's
# llvmpipe, from Debian's packages. Installs them when missing and running as
# root on Debian; elsewhere only says what to install (the renderer then reports
# GLUnavailableError, and its tests skip unless SHADOWMATH_REQUIRE_GL=1).
set -euo pipefail
PACKAGES="libegl1 libgl1 libgl1-mesa-dri"
command -v dpkg >/dev/null || exit 0
# shellcheck disable=SC2086  # word splitting of the package list is intended
if dpkg -s $PACKAGES >/dev/null 2>&1; then
    exit 0
fi
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    echo "installing headless OpenGL: $PACKAGES"
    apt-get update -qq
    # shellcheck disable=SC2086
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $PACKAGES
else
    echo "note: the reference renderer needs: sudo apt-get install $PACKAGES" >&2
fi
