/* Helpers shared by the cadr sample programs: failing with cadr's message, matrices, and
 * simple CAD-like shapes built as host arrays. */
#ifndef CADR_SAMPLE_H
#define CADR_SAMPLE_H

#include "cadr.h"

/* Exits with the call, the result's name and cadr's message when `call` fails. */
#define CADR_CHECK(call) sample_check((call), #call, __FILE__, __LINE__)

void sample_check(enum CadrResult result, const char *call, const char *file, int line);

/* Prints cadr's warnings and errors (what a load left out, validation errors) to stderr. */
void sample_print_messages(void);

/* A context with the default options, the window system's instance `extensions` (NULL and 0
 * for none) and, for self-tests, `validation`; cadr's warnings and errors printed. */
CadrContext sample_context(const char *const *extensions, uint32_t extension_count,
                           int validation);

/* A new scene holding `source` (a file or a generator such as "gen:demo") under its root, and
 * its bounds. */
CadrScene sample_load(const char *source, struct CadrBounds *bounds);

/* Highlights geo node `node` of `scene` (`on`) or takes its highlight away; 0 is no node. */
void sample_set_highlighted(CadrScene scene, CadrNode node, int on);

/* For the samples' self-tests: renders `scene` seen by `camera` offscreen at `width` x `height`
 * into the PNG `path`, the reference a test compares a window with. */
void sample_save_offscreen(CadrContext context, CadrScene scene, const struct CadrCamera *camera,
                           uint32_t width, uint32_t height, const char *path);

/* For the samples' self-tests: prints "screenshot ready WxH" and waits until a line arrives on
 * stdin (the test has grabbed the window). */
void sample_screenshot_ready(uint32_t width, uint32_t height);

/* Column-major 4x4 matrices. */
void sample_identity(double m[16]);
void sample_translation(double m[16], double x, double y, double z);
/* Rotation about +Z by `radians`, then translation. */
void sample_rotate_z_translate(double m[16], double radians, double x, double y, double z);

/* A box of the given half sizes, one part per pair of opposite faces (3 parts). */
CadrGeometry sample_box(CadrScene scene, const char *name, float hx, float hy, float hz);
/* A cylinder along +Z of `radius` and `height` with `segments` sides: side and caps (2 parts). */
CadrGeometry sample_cylinder(CadrScene scene, const char *name, float radius, float height,
                             int segments);
/* A material of a linear RGB color. */
CadrMaterial sample_material(CadrScene scene, const char *name, float r, float g, float b,
                             float metallic, float roughness);

#endif
