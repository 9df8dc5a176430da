//! Render targets, shader variants and pipelines of the wgpu camera.
//!
//! The geometry shader (`scene.wgsl`) is specialised per set of outputs, so a depth-only
//! frame runs a shader that computes and writes nothing else.

use super::tessellate::Vertex;

/// WGSL source of the geometry pass.
const SCENE_WGSL: &str = include_str!("scene.wgsl");
/// WGSL source of the shadow-map pass.
const SHADOW_WGSL: &str = include_str!("shadow.wgsl");

/// Format of the scene depth buffer (reversed depth: near = 1, far = 0).
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Format of the shadow map.
pub(crate) const SHADOW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// One colour attachment of the geometry pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) enum Target {
    /// Tone-mapped colour (sRGB RGBA8).
    Rgb,
    /// Camera-frame z (R32Float).
    Depth,
    /// Camera-frame normal (RGBA16Float).
    Normal,
    /// Semantic and instance id (RG32Uint).
    Ids,
    /// Scene flow (RGBA32Float).
    SceneFlow,
    /// Optical flow (RG32Float).
    OpticalFlow,
}

impl Target {
    /// Every target, in attachment order.
    pub(crate) const ALL: [Target; 6] = [
        Target::Rgb,
        Target::Depth,
        Target::Normal,
        Target::Ids,
        Target::SceneFlow,
        Target::OpticalFlow,
    ];

    pub(crate) fn bit(self) -> u8 {
        1 << (self as u8)
    }

    pub(crate) fn format(self) -> wgpu::TextureFormat {
        use wgpu::TextureFormat as F;
        match self {
            Target::Rgb => F::Rgba8UnormSrgb,
            Target::Depth => F::R32Float,
            Target::Normal => F::Rgba16Float,
            Target::Ids => F::Rg32Uint,
            Target::SceneFlow => F::Rgba32Float,
            Target::OpticalFlow => F::Rg32Float,
        }
    }

    /// Bytes of one texel when copied to a buffer.
    pub(crate) fn texel_bytes(self) -> u32 {
        match self {
            Target::Rgb | Target::Depth => 4,
            Target::Normal | Target::Ids | Target::OpticalFlow => 8,
            Target::SceneFlow => 16,
        }
    }

    fn flag(self) -> &'static str {
        match self {
            Target::Rgb => "RGB",
            Target::Depth => "DEPTH",
            Target::Normal => "NORMAL",
            Target::Ids => "IDS",
            Target::SceneFlow => "SFLOW",
            Target::OpticalFlow => "OFLOW",
        }
    }

    /// The clear value: 0 everywhere except the sky colour of RGB.
    pub(crate) fn clear(self, sky_linear: [f64; 3]) -> wgpu::Color {
        match self {
            Target::Rgb => wgpu::Color {
                r: sky_linear[0],
                g: sky_linear[1],
                b: sky_linear[2],
                a: 1.0,
            },
            _ => wgpu::Color::TRANSPARENT,
        }
    }

    /// The targets in `mask`, in attachment order.
    pub(crate) fn in_mask(mask: u8) -> impl Iterator<Item = Target> {
        Target::ALL.into_iter().filter(move |t| mask & t.bit() != 0)
    }
}

/// Bytes per sample the attachments in `mask` take, as the device limit counts them.
pub(crate) fn bytes_per_sample(mask: u8) -> u32 {
    let mut total = 0u32;
    for t in Target::in_mask(mask) {
        let f = t.format();
        let align = f.target_component_alignment().unwrap_or(1);
        total = total.div_ceil(align) * align + f.target_pixel_byte_cost().unwrap_or(16);
    }
    total
}

/// Resolves `#if A B` / `#else` / `#endif` lines (a block is kept when any listed flag is in
/// `flags`).
pub(crate) fn preprocess(src: &str, flags: &[&str]) -> String {
    let mut out = String::with_capacity(src.len());
    // (block active, condition of the `#if`, parent active)
    let mut stack: Vec<(bool, bool, bool)> = Vec::new();
    let active = |stack: &Vec<(bool, bool, bool)>| stack.last().is_none_or(|s| s.0);
    for line in src.lines() {
        let t = line.trim_start();
        if let Some(rest) = t.strip_prefix("#if ") {
            let cond = rest.split_whitespace().any(|f| flags.contains(&f));
            let parent = active(&stack);
            stack.push((parent && cond, cond, parent));
        } else if t.starts_with("#else") {
            if let Some(top) = stack.last_mut() {
                top.0 = top.2 && !top.1;
            }
        } else if t.starts_with("#endif") {
            stack.pop();
        } else if active(&stack) {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// The geometry shader for the targets in `mask`.
pub(crate) fn scene_shader_source(mask: u8, pbr: bool, shadow: bool) -> String {
    let mut flags: Vec<&str> = Target::in_mask(mask).map(Target::flag).collect();
    if pbr {
        flags.push("PBR");
    }
    if shadow && mask & Target::Rgb.bit() != 0 {
        flags.push("SHADOW");
    }
    let mut src = preprocess(SCENE_WGSL, &flags);
    for (loc, t) in Target::in_mask(mask).enumerate() {
        src = src.replace(&format!("LOC_{}", t.flag()), &loc.to_string());
    }
    src
}

/// The vertex buffer layout shared by every pipeline.
pub(crate) fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    const ATTRIBUTES: [wgpu::VertexAttribute; 3] = wgpu::vertex_attr_array![
        0 => Float32x3,
        1 => Snorm16x4,
        2 => Uint32,
    ];
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as wgpu::BufferAddress,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &ATTRIBUTES,
    }
}

/// Bind group layout of the geometry pass (with the shadow map and its sampler when
/// `shadow`).
pub(crate) fn scene_bind_group_layout(device: &wgpu::Device, shadow: bool) -> wgpu::BindGroupLayout {
    let vf = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT;
    let storage = |binding, visibility| wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let mut entries = vec![
        wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: vf,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        },
        storage(1, wgpu::ShaderStages::VERTEX),
        storage(2, wgpu::ShaderStages::FRAGMENT),
    ];
    if shadow {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 3,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Depth,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        });
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 4,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
            count: None,
        });
    }
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("hearth camera scene"),
        entries: &entries,
    })
}

/// Bind group layout of the shadow pass.
pub(crate) fn shadow_bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("hearth camera shadow"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    })
}

/// What distinguishes geometry pipelines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct PipelineKey {
    pub mask: u8,
    pub samples: u32,
    pub cull: bool,
}

/// Creates a geometry pipeline writing the targets of `key.mask` (mask 0: the depth-only
/// pre-pass).
pub(crate) fn scene_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    key: PipelineKey,
    pbr: bool,
    shadow: bool,
) -> wgpu::RenderPipeline {
    let source = scene_shader_source(key.mask, pbr, shadow);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("hearth camera scene"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("hearth camera scene"),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let targets: Vec<Option<wgpu::ColorTargetState>> = Target::in_mask(key.mask)
        .map(|t| {
            Some(wgpu::ColorTargetState {
                format: t.format(),
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        })
        .collect();
    // Colour is shaded once per pixel: a depth pre-pass (mask 0) fills the depth buffer, the
    // colour pass then only draws the nearest surface. Other passes test and write as usual.
    let (write, compare) = if key.mask == 0 {
        (true, wgpu::CompareFunction::Greater)
    } else if key.mask & Target::Rgb.bit() != 0 {
        (false, wgpu::CompareFunction::GreaterEqual)
    } else {
        (true, wgpu::CompareFunction::Greater)
    };
    let fragment = (key.mask != 0).then(|| wgpu::FragmentState {
        module: &module,
        entry_point: Some("fs_main"),
        compilation_options: Default::default(),
        targets: &targets,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("hearth camera scene"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(vertex_layout())],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            front_face: wgpu::FrontFace::Ccw,
            cull_mode: key.cull.then_some(wgpu::Face::Back),
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(write),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState {
            count: key.samples,
            ..Default::default()
        },
        fragment,
        multiview_mask: None,
        cache: None,
    })
}

/// Creates the depth-only shadow-map pipeline.
pub(crate) fn shadow_pipeline(device: &wgpu::Device, layout: &wgpu::BindGroupLayout) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("hearth camera shadow"),
        source: wgpu::ShaderSource::Wgsl(SHADOW_WGSL.into()),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("hearth camera shadow"),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("hearth camera shadow"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_shadow"),
            compilation_options: Default::default(),
            buffers: &[Some(vertex_layout())],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            // Both faces cast: open meshes and thin slabs shadow too.
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: SHADOW_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: wgpu::DepthBiasState {
                constant: 2,
                slope_scale: 2.0,
                clamp: 0.0,
            },
        }),
        multisample: Default::default(),
        fragment: None,
        multiview_mask: None,
        cache: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preprocessor_keeps_blocks_of_any_listed_flag() {
        let src = "a\n#if X Y\nb\n#if Z\nc\n#else\nd\n#endif\n#endif\ne\n";
        assert_eq!(preprocess(src, &["Y"]), "a\nb\nd\ne\n");
        assert_eq!(preprocess(src, &["X", "Z"]), "a\nb\nc\ne\n");
        assert_eq!(preprocess(src, &[]), "a\ne\n");
    }

    #[test]
    fn every_shader_variant_parses_and_validates() {
        for mask in 0u8..64 {
            for (pbr, shadow) in [(true, true), (false, false), (true, false)] {
                let src = scene_shader_source(mask, pbr, shadow);
                let module = naga_check(&src);
                assert!(module.is_ok(), "mask {mask}: {}", module.unwrap_err());
            }
        }
        assert!(naga_check(SHADOW_WGSL).is_ok());
    }

    fn naga_check(src: &str) -> Result<(), String> {
        let module = wgpu::naga::front::wgsl::parse_str(src).map_err(|e| e.emit_to_string(src))?;
        wgpu::naga::valid::Validator::new(
            wgpu::naga::valid::ValidationFlags::all(),
            wgpu::naga::valid::Capabilities::default(),
        )
        .validate(&module)
        .map_err(|e| format!("{e:?}"))?;
        Ok(())
    }
}
