//! The hand-written bindings against the Vulkan registry: every bound struct has the members
//! of its `vk.xml` definition, in order, at the offsets a C compiler gives them on this
//! target, and every bound constant has the registry's value. The registry's definitions are
//! kept in `vk_device_generated_commands.xml`, an excerpt of `vk.xml`.

use std::mem::{align_of, offset_of, size_of};

use ash::vk;
use cadr_vk_ext::device_generated_commands as dgc;

const REGISTRY: &str = include_str!("vk_device_generated_commands.xml");

/// One member of a registry struct: its C type, whether it is a pointer, its name.
#[derive(Debug)]
struct Member {
    ty: String,
    pointer: bool,
    name: String,
}

fn between<'a>(text: &'a str, open: &str, close: &str) -> Option<&'a str> {
    let start = text.find(open)? + open.len();
    let end = start + text[start..].find(close)?;
    Some(&text[start..end])
}

/// The members of the struct or union `name`, from the registry excerpt.
fn members(name: &str) -> Vec<Member> {
    let marker = format!(" name=\"{name}\"");
    let start = REGISTRY
        .find(&format!("category=\"struct\"{marker}"))
        .or_else(|| REGISTRY.find(&format!("category=\"union\"{marker}")))
        .unwrap_or_else(|| panic!("{name} is not in the registry excerpt"));
    let body = between(&REGISTRY[start..], ">", "</type>\n").expect("the definition ends");
    body.split("<member")
        .skip(1)
        .map(|member| {
            let member = member.split("</member>").next().expect("a member");
            let ty = between(member, "<type>", "</type>").expect("a member type");
            let after_type = member.split("</type>").nth(1).expect("text after the type");
            Member {
                ty: ty.to_owned(),
                pointer: after_type.contains('*'),
                name: between(member, "<name>", "</name>")
                    .expect("a member name")
                    .to_owned(),
            }
        })
        .collect()
}

/// Size and alignment of a C type on this (64-bit) target.
fn c_layout(ty: &str, pointer: bool) -> (usize, usize) {
    if pointer {
        return (8, 8);
    }
    match ty {
        "uint32_t"
        | "int32_t"
        | "VkBool32"
        | "VkStructureType"
        | "VkShaderStageFlags"
        | "VkIndirectCommandsLayoutUsageFlagsEXT"
        | "VkIndirectCommandsTokenTypeEXT"
        | "VkIndirectExecutionSetInfoTypeEXT" => (4, 4),
        "uint64_t"
        | "VkDeviceAddress"
        | "VkDeviceSize"
        | "VkPipeline"
        | "VkPipelineLayout"
        | "VkIndirectExecutionSetEXT"
        | "VkIndirectCommandsLayoutEXT" => (8, 8),
        "VkIndirectCommandsTokenDataEXT"
        | "VkIndirectExecutionSetInfoEXT"
        | "VkPushConstantRange" => {
            let fields = struct_layout(ty);
            (fields.size, fields.align)
        }
        other => panic!("the test does not know the C type {other}"),
    }
}

/// A struct's C layout: its members' snake-case names and offsets, its size and alignment.
struct Layout {
    fields: Vec<(String, usize)>,
    size: usize,
    align: usize,
}

fn snake_case(name: &str) -> String {
    let mut out = String::new();
    for c in name.chars() {
        if c.is_ascii_uppercase() {
            out.push('_');
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(c);
        }
    }
    out
}

fn struct_layout(name: &str) -> Layout {
    let is_union = REGISTRY.contains(&format!("category=\"union\" name=\"{name}\""));
    let (mut offset, mut align, mut size): (usize, usize, usize) = (0, 1, 0);
    let mut fields = Vec::new();
    for member in members(name) {
        let (member_size, member_align) = c_layout(&member.ty, member.pointer);
        align = align.max(member_align);
        if is_union {
            size = size.max(member_size);
            fields.push((snake_case(&member.name), 0));
        } else {
            offset = offset.next_multiple_of(member_align);
            fields.push((snake_case(&member.name), offset));
            offset += member_size;
            size = offset;
        }
    }
    Layout {
        fields,
        size: size.next_multiple_of(align),
        align,
    }
}

/// A Rust binding's layout: size, alignment and the offsets of the fields named, in order.
macro_rules! rust_layout {
    ($ty:ty, [$($field:ident),* $(,)?]) => {
        (
            size_of::<$ty>(),
            align_of::<$ty>(),
            vec![$((stringify!($field), offset_of!($ty, $field))),*],
        )
    };
}

/// Registry member names whose Rust field is named otherwise (`type` is a keyword).
fn rust_name(registry: &str) -> String {
    match registry {
        "type" => "ty".into(),
        other => other.into(),
    }
}

fn check(name: &str, (size, align, fields): (usize, usize, Vec<(&str, usize)>)) {
    let c = struct_layout(name);
    let expected: Vec<(String, usize)> = c
        .fields
        .iter()
        .map(|(field, offset)| (rust_name(field), *offset))
        .collect();
    let actual: Vec<(String, usize)> = fields
        .iter()
        .map(|(field, offset)| ((*field).to_owned(), *offset))
        .collect();
    assert_eq!(actual, expected, "{name}: members and offsets");
    assert_eq!(
        (size, align),
        (c.size, c.align),
        "{name}: size and alignment"
    );
}

#[test]
fn every_bound_struct_has_the_registry_layout() {
    check(
        "VkPhysicalDeviceDeviceGeneratedCommandsFeaturesEXT",
        rust_layout!(
            dgc::PhysicalDeviceFeatures<'static>,
            [
                s_type,
                p_next,
                device_generated_commands,
                dynamic_generated_pipeline_layout
            ]
        ),
    );
    check(
        "VkGeneratedCommandsMemoryRequirementsInfoEXT",
        rust_layout!(
            dgc::MemoryRequirementsInfo<'static>,
            [
                s_type,
                p_next,
                indirect_execution_set,
                indirect_commands_layout,
                max_sequence_count,
                max_draw_count
            ]
        ),
    );
    check(
        "VkGeneratedCommandsInfoEXT",
        rust_layout!(
            dgc::GeneratedCommandsInfo<'static>,
            [
                s_type,
                p_next,
                shader_stages,
                indirect_execution_set,
                indirect_commands_layout,
                indirect_address,
                indirect_address_size,
                preprocess_address,
                preprocess_size,
                max_sequence_count,
                sequence_count_address,
                max_draw_count,
            ]
        ),
    );
    check(
        "VkIndirectCommandsLayoutCreateInfoEXT",
        rust_layout!(
            dgc::LayoutCreateInfo<'static>,
            [
                s_type,
                p_next,
                flags,
                shader_stages,
                indirect_stride,
                pipeline_layout,
                token_count,
                p_tokens
            ]
        ),
    );
    check(
        "VkIndirectCommandsLayoutTokenEXT",
        rust_layout!(
            dgc::LayoutToken<'static>,
            [s_type, p_next, ty, data, offset]
        ),
    );
    check(
        "VkGeneratedCommandsPipelineInfoEXT",
        rust_layout!(
            dgc::GeneratedCommandsPipelineInfo<'static>,
            [s_type, p_next, pipeline]
        ),
    );
    check(
        "VkIndirectCommandsExecutionSetTokenEXT",
        rust_layout!(dgc::ExecutionSetToken, [ty, shader_stages]),
    );
    check(
        "VkIndirectCommandsPushConstantTokenEXT",
        rust_layout!(dgc::PushConstantToken, [update_range]),
    );
    check(
        "VkPushConstantRange",
        rust_layout!(vk::PushConstantRange, [stage_flags, offset, size]),
    );
    check(
        "VkIndirectExecutionSetPipelineInfoEXT",
        rust_layout!(
            dgc::ExecutionSetPipelineInfo<'static>,
            [s_type, p_next, initial_pipeline, max_pipeline_count]
        ),
    );
    check(
        "VkIndirectExecutionSetCreateInfoEXT",
        rust_layout!(
            dgc::ExecutionSetCreateInfo<'static>,
            [s_type, p_next, ty, info]
        ),
    );
    check(
        "VkWriteIndirectExecutionSetPipelineEXT",
        rust_layout!(
            dgc::WriteExecutionSetPipeline<'static>,
            [s_type, p_next, index, pipeline]
        ),
    );
    // The unions: as large and aligned as a pointer, each member a pointer.
    let union = struct_layout("VkIndirectCommandsTokenDataEXT");
    assert_eq!(
        (
            size_of::<dgc::TokenData<'static>>(),
            align_of::<dgc::TokenData<'static>>()
        ),
        (union.size, union.align)
    );
    let union = struct_layout("VkIndirectExecutionSetInfoEXT");
    assert_eq!(
        (
            size_of::<dgc::ExecutionSetInfo<'static>>(),
            align_of::<dgc::ExecutionSetInfo<'static>>()
        ),
        (union.size, union.align)
    );
    // Handles are 64-bit non-dispatchable handles.
    assert_eq!(size_of::<dgc::IndirectCommandsLayout>(), 8);
    assert_eq!(size_of::<dgc::IndirectExecutionSet>(), 8);
}

/// The value of the registry's enum `name`: a value, a bit position, or an offset in the
/// range of the extension that defines it.
fn extension_enum(name: &str) -> i64 {
    let at = REGISTRY
        .find(&format!("name=\"{name}\""))
        .unwrap_or_else(|| panic!("{name} is not in the excerpt"));
    let line_start = REGISTRY[..at].rfind('<').expect("the enum's tag");
    let tag = &REGISTRY[line_start..at];
    if let Some(offset) = between(tag, "offset=\"", "\"") {
        let offset: i64 = offset.parse().expect("a numeric offset");
        let number: i64 = between(tag, "extnumber=\"", "\"")
            .or_else(|| {
                let start = REGISTRY[..at].rfind("<extension name=")?;
                between(&REGISTRY[start..], "number=\"", "\"")
            })
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{name}: no extension number"));
        1_000_000_000 + (number - 1) * 1000 + offset
    } else if let Some(bit) = between(tag, "bitpos=\"", "\"") {
        1 << bit.parse::<i64>().expect("a numeric bit")
    } else {
        between(tag, "value=\"", "\"")
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("{name} has no value"))
    }
}

#[test]
fn every_bound_constant_has_the_registry_value() {
    for (name, value) in [
        (
            "VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DEVICE_GENERATED_COMMANDS_FEATURES_EXT",
            dgc::STRUCTURE_TYPE_FEATURES,
        ),
        (
            "VK_STRUCTURE_TYPE_GENERATED_COMMANDS_MEMORY_REQUIREMENTS_INFO_EXT",
            dgc::STRUCTURE_TYPE_MEMORY_REQUIREMENTS_INFO,
        ),
        (
            "VK_STRUCTURE_TYPE_GENERATED_COMMANDS_INFO_EXT",
            dgc::STRUCTURE_TYPE_GENERATED_COMMANDS_INFO,
        ),
        (
            "VK_STRUCTURE_TYPE_INDIRECT_COMMANDS_LAYOUT_CREATE_INFO_EXT",
            dgc::STRUCTURE_TYPE_LAYOUT_CREATE_INFO,
        ),
        (
            "VK_STRUCTURE_TYPE_INDIRECT_COMMANDS_LAYOUT_TOKEN_EXT",
            dgc::STRUCTURE_TYPE_LAYOUT_TOKEN,
        ),
        (
            "VK_STRUCTURE_TYPE_GENERATED_COMMANDS_PIPELINE_INFO_EXT",
            dgc::STRUCTURE_TYPE_GENERATED_COMMANDS_PIPELINE_INFO,
        ),
        (
            "VK_STRUCTURE_TYPE_INDIRECT_EXECUTION_SET_CREATE_INFO_EXT",
            dgc::STRUCTURE_TYPE_EXECUTION_SET_CREATE_INFO,
        ),
        (
            "VK_STRUCTURE_TYPE_WRITE_INDIRECT_EXECUTION_SET_PIPELINE_EXT",
            dgc::STRUCTURE_TYPE_WRITE_EXECUTION_SET_PIPELINE,
        ),
        (
            "VK_STRUCTURE_TYPE_INDIRECT_EXECUTION_SET_PIPELINE_INFO_EXT",
            dgc::STRUCTURE_TYPE_EXECUTION_SET_PIPELINE_INFO,
        ),
    ] {
        assert_eq!(i64::from(value.as_raw()), extension_enum(name), "{name}");
    }
    assert_eq!(
        dgc::BUFFER_USAGE_2_PREPROCESS_BUFFER.as_raw() as i64,
        extension_enum("VK_BUFFER_USAGE_2_PREPROCESS_BUFFER_BIT_EXT")
    );
    assert_eq!(
        dgc::PIPELINE_CREATE_2_INDIRECT_BINDABLE.as_raw() as i64,
        extension_enum("VK_PIPELINE_CREATE_2_INDIRECT_BINDABLE_BIT_EXT")
    );
    for (token, name) in [
        (dgc::TokenType::DRAW_INDEXED, "DRAW_INDEXED"),
        (dgc::TokenType::EXECUTION_SET, "EXECUTION_SET"),
        (dgc::TokenType::PUSH_CONSTANT, "PUSH_CONSTANT"),
    ] {
        assert_eq!(
            i64::from(token.as_raw()),
            extension_enum(&format!("VK_INDIRECT_COMMANDS_TOKEN_TYPE_{name}_EXT"))
        );
    }
    assert_eq!(
        i64::from(dgc::EXECUTION_SET_OF_PIPELINES),
        extension_enum("VK_INDIRECT_EXECUTION_SET_INFO_TYPE_PIPELINES_EXT")
    );
    // The structures of VK_KHR_maintenance5 cadr chains, as ash 0.38 numbers them.
    assert_eq!(
        i64::from(vk::StructureType::PHYSICAL_DEVICE_MAINTENANCE_5_FEATURES_KHR.as_raw()),
        extension_enum("VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_5_FEATURES")
    );
    assert_eq!(
        i64::from(vk::StructureType::BUFFER_USAGE_FLAGS_2_CREATE_INFO_KHR.as_raw()),
        extension_enum("VK_STRUCTURE_TYPE_BUFFER_USAGE_FLAGS_2_CREATE_INFO")
    );
    assert_eq!(
        i64::from(vk::StructureType::PIPELINE_CREATE_FLAGS_2_CREATE_INFO_KHR.as_raw()),
        extension_enum("VK_STRUCTURE_TYPE_PIPELINE_CREATE_FLAGS_2_CREATE_INFO")
    );
    assert_eq!(dgc::NAME.to_str(), Ok("VK_EXT_device_generated_commands"));
}
