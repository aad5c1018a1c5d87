#!/usr/bin/env bash
# Installs what a fresh Debian/Ubuntu machine lacks to run Cohort: a Vulkan loader, a
# Vulkan driver (Mesa's software driver lavapipe, when no driver is installed), SPIR-V
# tools and the Vulkan validation layers; for `cohort view`, the X11 client libraries it
# loads at run time and Xvfb (its tests open the window on a virtual display). Does
# nothing when all are present.
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
if [ ${#need[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "installing: ${need[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq $(printf '%s\n' "${need[@]}" | sort -u) >/dev/null
fi
