#!/usr/bin/env bash
# Installs what a fresh Debian/Ubuntu machine lacks to run Cohort: a Vulkan loader, a
# Vulkan driver (Mesa's software driver lavapipe, when no driver is installed), SPIR-V
# tools and the Vulkan validation layers; for `cohort view`, the X11 client libraries it
# loads at run time and Xvfb (its tests open the window on a virtual display). Does
# nothing when all are present.
#
# On Debian 12 (bookworm) lavapipe comes from bookworm-backports (Mesa 25, which the
# script adds as an apt source): it runs the renderer's kernels about 1.7x faster than
# bookworm's Mesa 22 (BENCHMARKS.md, "Software driver"). COHORT_NO_BACKPORTS=1 keeps
# bookworm's own.
set -euo pipefail
need=()
ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1' || need+=(libvulkan1)
ls /usr/share/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1 || [ -n "${COHORT_NO_LAVAPIPE:-}" ] || need+=(mesa-vulkan-drivers)
command -v spirv-val >/dev/null || need+=(spirv-tools)
[ -e /usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json ] || need+=(vulkan-validationlayers)
# cohort view: winit and softbuffer open these with dlopen; Xvfb runs its tests.
for lib in libX11.so.6:libx11-6 libX11-xcb.so.1:libx11-xcb1 libXcursor.so.1:libxcursor1 \
    libXrandr.so.2:libxrandr2 libXi.so.6:libxi6 libxkbcommon-x11.so.0:libxkbcommon-x11-0; do
  ldconfig -p 2>/dev/null | grep -q "${lib%%:*}" || need+=("${lib#*:}")
done
command -v Xvfb >/dev/null || need+=(xvfb)
codename=$(. /etc/os-release 2>/dev/null && echo "${VERSION_CODENAME:-}")
backports=""
if [ "$codename" = bookworm ] && [ -z "${COHORT_NO_BACKPORTS:-}" ]; then
  backports=bookworm-backports
fi
if [ ${#need[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "installing: ${need[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  lavapipe=0
  printf '%s\n' "${need[@]}" | grep -qx mesa-vulkan-drivers && lavapipe=1
  if [ $lavapipe = 1 ] && [ -n "$backports" ]; then
    list=/etc/apt/sources.list.d/cohort-$backports.list
    [ -e "$list" ] || echo "deb http://deb.debian.org/debian $backports main" | $sudo tee "$list" >/dev/null
  fi
  $sudo apt-get update -qq
  rest=$(printf '%s\n' "${need[@]}" | grep -vx mesa-vulkan-drivers | sort -u || true)
  [ -z "$rest" ] || $sudo apt-get install -y -qq $rest >/dev/null
  if [ $lavapipe = 1 ]; then
    if [ -n "$backports" ]; then
      $sudo apt-get install -y -qq -t "$backports" mesa-vulkan-drivers >/dev/null
    else
      $sudo apt-get install -y -qq mesa-vulkan-drivers >/dev/null
    fi
  fi
elif [ -n "$backports" ] && dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null | grep -q '^22\.'; then
  echo "note: lavapipe is bookworm's Mesa 22; Mesa 25 from $backports runs Cohort's kernels about" \
    "1.7x faster (apt-get install -t $backports mesa-vulkan-drivers)" >&2
fi
