//! No branch or loop bound of the renderer's shaders depends on a uniform.
//!
//! Lavapipe (Mesa 22, the rasterizer CI and machines without a GPU use) inlines the values of
//! uniforms that decide control flow into the shader and compiles a new one whenever they are
//! bound again, which for per-object uniforms is every draw: about 2 ms per draw with a warm
//! disk cache and 90 ms without one. The shaders weigh such terms by the uniform instead. This
//! test parses each shader and follows which values derive from a uniform (through locals and
//! calls), failing on an `if`, `switch` or loop exit that tests one.

use naga::{AddressSpace, Expression, Function, Handle, Module, Statement};

const SHADERS: [(&str, &str); 2] = [
    ("scene.wgsl", include_str!("../../src/scene.wgsl")),
    ("upscale.wgsl", include_str!("../../src/upscale.wgsl")),
];

/// Where each function of `module` branches on a value derived from a uniform.
fn uniform_branches(module: &Module) -> Vec<String> {
    // Which functions read a uniform, directly or through a call, to a fixed point.
    let mut reads: Vec<bool> = module
        .functions
        .iter()
        .map(|(_, f)| reads_uniform_directly(module, f))
        .collect();
    loop {
        let mut changed = false;
        for (i, (_, f)) in module.functions.iter().enumerate() {
            if !reads[i] && calls(&f.body).iter().any(|h| reads[h.index()]) {
                reads[i] = true;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let mut found = Vec::new();
    let all = module
        .functions
        .iter()
        .map(|(_, f)| f)
        .chain(module.entry_points.iter().map(|e| &e.function));
    for f in all {
        let tainted = tainted_expressions(module, f, &reads);
        let name = f.name.clone().unwrap_or_default();
        branches(&f.body, &mut |kind, condition| {
            if tainted[condition.index()] {
                found.push(format!("{name}: {kind}"));
            }
        });
    }
    found
}

fn reads_uniform_directly(module: &Module, f: &Function) -> bool {
    f.expressions.iter().any(|(_, e)| {
        matches!(e, Expression::GlobalVariable(g) if module.global_variables[*g].space == AddressSpace::Uniform)
    })
}

fn calls(block: &naga::Block) -> Vec<Handle<Function>> {
    let mut out = Vec::new();
    visit(block, &mut |s| {
        if let Statement::Call { function, .. } = s {
            out.push(*function);
        }
    });
    out
}

/// Calls `f` on every statement of `block`, nested ones included.
fn visit(block: &naga::Block, f: &mut impl FnMut(&Statement)) {
    for s in block.iter() {
        f(s);
        match s {
            Statement::Block(b) => visit(b, f),
            Statement::If { accept, reject, .. } => {
                visit(accept, f);
                visit(reject, f);
            }
            Statement::Switch { cases, .. } => cases.iter().for_each(|c| visit(&c.body, f)),
            Statement::Loop { body, continuing, .. } => {
                visit(body, f);
                visit(continuing, f);
            }
            _ => {}
        }
    }
}

fn branches(block: &naga::Block, found: &mut impl FnMut(&'static str, Handle<Expression>)) {
    visit(block, &mut |s| match s {
        Statement::If { condition, .. } => found("if", *condition),
        Statement::Switch { selector, .. } => found("switch", *selector),
        Statement::Loop {
            break_if: Some(condition),
            ..
        } => found("loop exit", *condition),
        _ => {}
    });
}

/// Which expressions of `f` derive from a uniform. Values stored in a local taint the local;
/// a call's result is tainted when an argument is or the callee reads a uniform.
fn tainted_expressions(module: &Module, f: &Function, reads: &[bool]) -> Vec<bool> {
    let mut expr = vec![false; f.expressions.len()];
    let mut local = vec![false; f.local_variables.len()];
    loop {
        let before = (expr.clone(), local.clone());
        for (h, e) in f.expressions.iter() {
            let t = |x: &Handle<Expression>| expr[x.index()];
            let value = match e {
                Expression::GlobalVariable(g) => module.global_variables[*g].space == AddressSpace::Uniform,
                Expression::LocalVariable(l) => local[l.index()],
                Expression::Compose { components, .. } => components.iter().any(t),
                Expression::Access { base, index } => t(base) || t(index),
                Expression::AccessIndex { base, .. } => t(base),
                Expression::Splat { value, .. } => t(value),
                Expression::Swizzle { vector, .. } => t(vector),
                Expression::Load { pointer } => t(pointer),
                Expression::Unary { expr: x, .. } => t(x),
                Expression::Binary { left, right, .. } => t(left) || t(right),
                Expression::Select {
                    condition,
                    accept,
                    reject,
                } => t(condition) || t(accept) || t(reject),
                Expression::Relational { argument, .. } => t(argument),
                Expression::Math {
                    arg,
                    arg1,
                    arg2,
                    arg3,
                    ..
                } => t(arg) || [arg1, arg2, arg3].into_iter().flatten().any(t),
                Expression::As { expr: x, .. } => t(x),
                Expression::Derivative { expr: x, .. } => t(x),
                Expression::ImageSample { coordinate, .. } => t(coordinate),
                Expression::ImageLoad { coordinate, .. } => t(coordinate),
                _ => false,
            };
            expr[h.index()] |= value;
        }
        visit(&f.body, &mut |s| match s {
            Statement::Store { pointer, value } if expr[value.index()] => {
                if let Some(l) = root_local(f, *pointer) {
                    local[l] = true;
                }
            }
            Statement::Call {
                function,
                arguments,
                result: Some(result),
            } if reads[function.index()] || arguments.iter().any(|a| expr[a.index()]) => {
                expr[result.index()] = true;
            }
            _ => {}
        });
        if (expr.clone(), local.clone()) == before {
            return expr;
        }
    }
}

fn root_local(f: &Function, mut pointer: Handle<Expression>) -> Option<usize> {
    loop {
        match &f.expressions[pointer] {
            Expression::LocalVariable(l) => return Some(l.index()),
            Expression::Access { base, .. } | Expression::AccessIndex { base, .. } => pointer = *base,
            _ => return None,
        }
    }
}

fn parse(name: &str, source: &str) -> Module {
    naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)))
}

#[test]
fn no_branch_of_the_renderers_shaders_tests_a_uniform() {
    for (name, source) in SHADERS {
        let found = uniform_branches(&parse(name, source));
        assert!(found.is_empty(), "{name} branches on uniforms: {found:?}");
    }
}

/// The check finds what the scene shader used to do: a branch on a per-object flag, a loop
/// bounded by a uniform count, a branch on a local set from a uniform, and a branch on what a
/// function that reads a uniform returns.
#[test]
fn the_check_finds_branches_on_uniforms() {
    let source = "
struct Object { flags: vec4<f32>, counts: vec4<u32> };
@group(0) @binding(0) var<uniform> object: Object;
fn rough() -> f32 { return object.flags.y; }
@fragment fn fs(@location(0) x: f32) -> @location(0) vec4<f32> {
    var out = x;
    if object.flags.x > 0.5 { out = out * 2.0; }
    for (var i = 0u; i < object.counts.x; i = i + 1u) { out = out + 1.0; }
    var r = 0.0;
    r = object.flags.z;
    if r > 0.0 { out = -out; }
    if rough() > 0.0 { out = out * 0.5; }
    for (var i = 0u; i < 4u; i = i + 1u) { out = out + select(0.0, 1.0, i < object.counts.y); }
    if x > 0.0 { out = out + 1.0; }
    return vec4<f32>(out);
}
";
    let found = uniform_branches(&parse("test", source));
    assert_eq!(found.len(), 4, "{found:?}");
    assert!(found.iter().all(|f| f == "fs: if"), "{found:?}");
}
