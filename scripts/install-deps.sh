#!/usr/bin/env bash
# Installs what a fresh Debian/Ubuntu machine lacks to run Cohort: a Vulkan loader, a
# Vulkan driver (Mesa's software driver lavapipe, when no driver is installed), SPIR-V
# tools and the Vulkan validation layers. Does nothing when all are present.
set -euo pipefail
need=()
ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1' || need+=(libvulkan1)
ls /usr/share/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1 || [ -n "${COHORT_NO_LAVAPIPE:-}" ] || need+=(mesa-vulkan-drivers)
command -v spirv-val >/dev/null || need+=(spirv-tools)
[ -e /usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json ] || need+=(vulkan-validationlayers)
if [ ${#need[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "installing: ${need[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq $(printf '%s\n' "${need[@]}" | sort -u) >/dev/null
fi
