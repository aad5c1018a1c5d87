//! SPIR-V float controls (`SPV_KHR_float_controls`, core in Vulkan 1.2): asks the driver to
//! keep f32 subnormals (`DenormPreserve`) and NaN, infinities and signed zeros
//! (`SignedZeroInfNanPreserve`) for a compute module. Without them a driver may flush
//! subnormals to zero and fold NaN-sensitive code (the H100 turned glam's NaN-propagating
//! `select(a > b, a, b)` into `fmax`, and computed `1.5 * 1e-40` as 0). naga 30 cannot emit
//! these modes, so they are added to its output here.

const OP_EXTENSION: u32 = 10;
const OP_ENTRY_POINT: u32 = 15;
const OP_EXECUTION_MODE: u32 = 16;
const OP_CAPABILITY: u32 = 17;
const CAP_DENORM_PRESERVE: u32 = 4464;
const CAP_SIGNED_ZERO_INF_NAN_PRESERVE: u32 = 4466;
const MODE_DENORM_PRESERVE: u32 = 4459;
const MODE_SIGNED_ZERO_INF_NAN_PRESERVE: u32 = 4461;
const EXTENSION: &str = "SPV_KHR_float_controls";

fn op(word_count: usize, opcode: u32) -> u32 {
    ((word_count as u32) << 16) | opcode
}

/// A SPIR-V literal string: UTF-8 bytes, NUL-terminated, padded to whole words.
fn literal(s: &str) -> Vec<u32> {
    let mut bytes = s.as_bytes().to_vec();
    bytes.push(0);
    bytes.resize(bytes.len().div_ceil(4) * 4, 0);
    bytes
        .chunks(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// `module` with, for 32-bit floats, the capability, extension and execution mode (for
/// every entry point) of each preservation asked for. A module that is not well-formed
/// SPIR-V is returned unchanged (pipeline creation then reports it).
pub(crate) fn preserve_f32(module: &[u32], subnormals: bool, nan_inf: bool) -> Vec<u32> {
    const HEADER: usize = 5;
    let wanted: Vec<(u32, u32)> = [
        (subnormals, (CAP_DENORM_PRESERVE, MODE_DENORM_PRESERVE)),
        (
            nan_inf,
            (
                CAP_SIGNED_ZERO_INF_NAN_PRESERVE,
                MODE_SIGNED_ZERO_INF_NAN_PRESERVE,
            ),
        ),
    ]
    .into_iter()
    .filter_map(|(on, cm)| on.then_some(cm))
    .collect();
    if module.len() < HEADER || wanted.is_empty() {
        return module.to_vec();
    }
    // Instruction boundaries, with their opcodes.
    let mut at = HEADER;
    let mut instructions = Vec::new();
    while at < module.len() {
        let count = (module[at] >> 16) as usize;
        if count == 0 || at + count > module.len() {
            return module.to_vec();
        }
        instructions.push((at, count, module[at] & 0xffff));
        at += count;
    }
    let entries: Vec<u32> = instructions
        .iter()
        .filter(|(_, _, o)| *o == OP_ENTRY_POINT)
        .map(|(i, _, _)| module[i + 2])
        .collect();
    // Capabilities first, then extensions, then (after the memory model and entry points)
    // execution modes: each addition goes before the first instruction of the next section.
    let first_after_caps = instructions
        .iter()
        .find(|(_, _, o)| *o != OP_CAPABILITY)
        .map_or(module.len(), |i| i.0);
    let first_mode = instructions
        .iter()
        .find(|(_, _, o)| *o == OP_EXECUTION_MODE)
        .map(|i| i.0)
        .or_else(|| {
            instructions
                .iter()
                .find(|(_, _, o)| {
                    *o > OP_EXECUTION_MODE
                        && *o != OP_CAPABILITY
                        && *o != OP_EXTENSION
                        && *o != OP_ENTRY_POINT
                        && *o != 11
                        && *o != 14
                })
                .map(|i| i.0)
        })
        .unwrap_or(module.len());
    let mut caps: Vec<u32> = wanted
        .iter()
        .flat_map(|&(c, _)| [op(2, OP_CAPABILITY), c])
        .collect();
    let name = literal(EXTENSION);
    caps.push(op(1 + name.len(), OP_EXTENSION));
    caps.extend(name);
    let mut modes = Vec::new();
    for e in entries {
        for &(_, mode) in &wanted {
            modes.extend([op(4, OP_EXECUTION_MODE), e, mode, 32]);
        }
    }
    let mut out = Vec::with_capacity(module.len() + caps.len() + modes.len());
    out.extend_from_slice(&module[..first_after_caps]);
    out.extend(caps);
    out.extend_from_slice(&module[first_after_caps..first_mode]);
    out.extend(modes);
    out.extend_from_slice(&module[first_mode..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The patched module of a real kernel disassembles and validates with the modes.
    #[test]
    fn patched_module_is_valid_spirv_with_the_modes() {
        let wgsl = "@group(0) @binding(0) var<storage, read_write> out: array<f32>;\n\
                    @compute @workgroup_size(64) fn main(@builtin(global_invocation_id) id: vec3<u32>) {\n\
                    out[id.x] = max(out[id.x], 1.5) * 1e-40;\n}";
        let module = naga::front::wgsl::parse_str(wgsl).unwrap();
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .unwrap();
        let opts = naga::back::spv::Options {
            lang_version: (1, 3),
            ..Default::default()
        };
        let spirv = naga::back::spv::write_vec(&module, &info, &opts, None).unwrap();
        assert_eq!(preserve_f32(&spirv, false, false), spirv);
        let only_nan = preserve_f32(&spirv, false, true);
        assert_eq!(only_nan.len(), spirv.len() + 2 + 7 + 4);
        let patched = preserve_f32(&spirv, true, true);
        // Two capabilities, the extension (7 words), two modes for the one entry point.
        assert_eq!(patched.len(), spirv.len() + 4 + 7 + 8);
        let text = rspirv::dr::load_words(&patched)
            .map(|m| rspirv::binary::Disassemble::disassemble(&m))
            .unwrap();
        assert!(text.contains("OpCapability DenormPreserve"), "{text}");
        assert!(
            text.contains("OpCapability SignedZeroInfNanPreserve"),
            "{text}"
        );
        assert!(
            text.contains("OpExtension \"SPV_KHR_float_controls\""),
            "{text}"
        );
        assert!(
            text.contains("OpExecutionMode %")
                && text.contains("DenormPreserve 32")
                && text.contains("SignedZeroInfNanPreserve 32"),
            "{text}"
        );
        // The rest is unchanged: removing the additions gives the original module back.
        assert_eq!(preserve_f32(&[1, 2], true, true), vec![1, 2]);
    }
}
