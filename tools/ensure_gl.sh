#!/usr/bin/env bash
# Headless graphics for the reference renderer (shadowmath.render): OpenGL through EGL
# (moderngl) and Vulkan (wgpu, shadowmath.render.webgpu), both on Mesa's llvmpipe, from
# Debian's packages. Installs them when missing and running as root on Debian; elsewhere
# only says what to install (the renderer then reports GLUnavailableError or
# WgpuUnavailableError, and its tests skip unless SHADOWMATH_REQUIRE_GL=1). Chromium draws
# the three.js integration's pages with software WebGL (tests/render/test_threejs_browser.py).
set -euo pipefail
PACKAGES="libegl1 libgl1 libgl1-mesa-dri mesa-vulkan-drivers chromium"
command -v dpkg >/dev/null || exit 0
# shellcheck disable=SC2086  # word splitting of the package list is intended
if dpkg -s $PACKAGES >/dev/null 2>&1; then
    exit 0
fi
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    echo "installing headless OpenGL and Vulkan: $PACKAGES"
    apt-get update -qq
    # shellcheck disable=SC2086
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $PACKAGES
else
    echo "note: the reference renderer needs: sudo apt-get install $PACKAGES" >&2
fi
