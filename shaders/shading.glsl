// Head-light shading for CAD: the light sits at the eye, surfaces are two-sided; the ambient
// term comes from a bright sky above and a darker ground below (world +Y is up), so that
// surfaces facing up and down read apart even where the head light meets them alike.
// base: linear RGBA; surface.x: metallic, surface.y: roughness; up: world +Y in view space.
const float CADR_SKY = 1.25;
const float CADR_GROUND = 0.55;

vec3 shade_headlight(vec3 view_position, vec3 view_normal, vec4 base, vec2 surface, vec4 light,
                     vec3 up) {
    vec3 to_eye = normalize(-view_position);
    float normal_length = length(view_normal);
    vec3 normal = normal_length > 0.0 ? view_normal / normal_length : to_eye;
    // Two-sided: the side seen is the one lit.
    if (dot(normal, to_eye) < 0.0) {
        normal = -normal;
    }
    float facing = dot(normal, to_eye);
    float sky = mix(CADR_GROUND, CADR_SKY, 0.5 + 0.5 * dot(normal, up));
    float metallic = clamp(surface.x, 0.0, 1.0);
    float roughness = clamp(surface.y, 0.03, 1.0);
    vec3 diffuse_color = base.rgb * (1.0 - 0.5 * metallic);
    vec3 specular_color = mix(vec3(0.04), base.rgb, metallic);
    // Blinn-Phong exponent from roughness; with a head light the half vector is the view vector.
    float shininess = 2.0 / (roughness * roughness * roughness * roughness) - 2.0;
    float specular = pow(facing, shininess) * (shininess + 8.0) / 32.0;
    vec3 color = base.rgb * light.x * sky + diffuse_color * facing * light.y
               + specular_color * min(specular, 4.0) * light.z;
    return pow(clamp(color, 0.0, 1.0), vec3(1.0 / 2.2));
}
