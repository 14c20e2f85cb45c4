// Planet and cloud-shell geometry. Mirrors src/atmosphere/mod.rs; see there for why the
// expressions are arranged this way (f32 at planetary radii).

struct Roots {
    hit: bool,
    t0: f32,
    t1: f32,
}

// Roots of the ray with the sphere at altitude h (radius R + h) of a planet centered at -up R.
fn sphere_roots(o: vec3f, d: vec3f, up: vec3f, radius: f32, h: f32) -> Roots {
    let b = dot(o, d) + radius * dot(up, d);
    let c = dot(o, o) + 2.0 * radius * dot(o, up) - 2.0 * radius * h - h * h;
    let disc = b * b - c;
    if (disc < 0.0) {
        return Roots(false, 0.0, 0.0);
    }
    let q = -b - select(-1.0, 1.0, b >= 0.0) * sqrt(disc);
    if (q == 0.0) {
        return Roots(true, 0.0, 0.0);
    }
    let t1 = q;
    let t2 = c / q;
    return Roots(true, min(t1, t2), max(t1, t2));
}

fn altitude(p: vec3f, up: vec3f, radius: f32) -> f32 {
    let num = dot(p, p) + 2.0 * radius * dot(p, up);
    return num / (length(p + up * radius) + radius);
}

struct Segments {
    count: u32,
    a: vec2f,
    b: vec2f,
}

// Intervals of the ray inside the shell [bottom, top], clipped to [0, max_t] and the ground.
fn shell_segments(o: vec3f, d: vec3f, up: vec3f, radius: f32, bottom: f32, top: f32, max_t: f32) -> Segments {
    let h = altitude(o, up, radius);
    let inner = sphere_roots(o, d, up, radius, bottom);
    let outer = sphere_roots(o, d, up, radius, top);
    var end = max_t;
    if (h >= 0.0) {
        let g = sphere_roots(o, d, up, radius, 0.0);
        if (g.hit && g.t0 > 0.0) {
            end = min(end, g.t0);
        }
    }
    var raw: array<vec2f, 2>;
    var n_raw = 0u;
    if (h < bottom) {
        if (inner.hit && outer.hit) {
            raw[0] = vec2f(inner.t1, outer.t1);
            n_raw = 1u;
        }
    } else if (outer.hit && outer.t1 > 0.0) {
        let start = select(0.0, max(outer.t0, 0.0), h > top);
        if (inner.hit && inner.t0 > start) {
            raw[0] = vec2f(start, inner.t0);
            raw[1] = vec2f(inner.t1, outer.t1);
            n_raw = 2u;
        } else {
            raw[0] = vec2f(start, outer.t1);
            n_raw = 1u;
        }
    }
    var out = Segments(0u, vec2f(0.0), vec2f(0.0));
    for (var i = 0u; i < n_raw; i++) {
        let s = vec2f(max(raw[i].x, 0.0), min(raw[i].y, end));
        if (s.y > s.x) {
            if (out.count == 0u) {
                out.a = s;
            } else {
                out.b = s;
            }
            out.count += 1u;
        }
    }
    return out;
}

// Interval of a ray inside a sphere of the given center and radius, clipped to [0, max_t].
fn ball_segment(o: vec3f, d: vec3f, center: vec3f, r: f32, max_t: f32) -> Segments {
    let oc = o - center;
    let b = dot(oc, d);
    let c = dot(oc, oc) - r * r;
    let disc = b * b - c;
    var out = Segments(0u, vec2f(0.0), vec2f(0.0));
    if (disc < 0.0) {
        return out;
    }
    let s = vec2f(max(-b - sqrt(disc), 0.0), min(-b + sqrt(disc), max_t));
    if (s.y > s.x) {
        out.a = s;
        out.count = 1u;
    }
    return out;
}
