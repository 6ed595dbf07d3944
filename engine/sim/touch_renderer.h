#pragma once
// Simulated GelSight touches on a triangle mesh (Taxim-style): place the
// sensor on a contact point, rasterise the object's height field over the
// sensor window, press the gel, deform it, shade it with a real sensor's
// polynomial table and background, add noise.
//
// Sensor frame: x = image columns, y = image rows, z = the sensor axis,
// pointing from the sensor into the object (x cross y = z). Pixel (row i,
// column j) looks along z from x * (j - (W-1)/2) * mm_per_px + y * (i -
// (H-1)/2) * mm_per_px off the centre line, so the sensor centre falls
// between the four middle pixels. The pose's translation is the sensor
// centre: the window centre on the undeformed gel plane, placed where the gel
// first touches the object anywhere over the window grown by 2 mm a side (the
// sensor body is bigger than its window), then moved press_mm along +z.
// Object points map into the sensor frame as R^T (p - t).
//
// Rendering: the object's nearest surface along z (front and back faces, an
// orthographic z-buffer at pixel centres) gives the undeformed intersection
// with the pressed gel plane (the contact mask); a Taxim-style drape
// (repeated Gaussian blurs, the gel never below the object) spreads it; the
// height h = depth_bg + indentation / mm_per_px (pixels) is shaded with the
// calibration's polynomial table exactly as data/gelsight/README.md says.
#include <array>
#include <memory>
#include <cstdint>
#include <optional>
#include <vector>

#include "engine/io/mesh.h"
#include "engine/sensor/calibration.h"

namespace vtloc::sim {

// The sensor model lives in engine/sensor (the engine's too); the simulator names it as before.
using sensor::Calibration;
using sensor::default_calibration_path;
using sensor::load_calibration;


using Vec3 = std::array<double, 3>;

struct SensorPose {
    std::array<double, 9> R{};  // row-major; columns are the sensor x, y, z axes in object coordinates
    Vec3 t{};                   // sensor centre, object units (mm)
};

struct TouchParams {
    double press_mm = 0.8;      // 0.3 .. 1.5 in the datasets
    double spin_deg = 0;        // rotation of the sensor about its axis
    double tilt_deg = 0;        // axis tilted this far away from -normal (<= 10)
    double tilt_dir_deg = 0;    // direction of the tilt, about the normal
};

// Appearance randomisation (sensor variety). Defaults = the calibrated sensor as it is.
struct Appearance {
    double brightness = 0;              // added to every channel, 0..255 scale
    std::array<double, 3> gain{1, 1, 1};  // per stored channel, applied to the background and the shading
    double blur_sigma_px = 0;           // extra optical blur of the final frame
    double noise_sigma = 2.0;           // Gaussian sensor noise, 0..255 scale
    // A user's own empty frame (height * width * 3, stored order); replaces real_bg.
    std::vector<float> background;
};

struct Touch {
    bool ok = false;              // false: rejected (reason says why)
    const char* reason = "";      // "centre ray misses the mesh", "gel hits other geometry first", ...
    SensorPose pose;
    // Ground truth: the centre line's first hit on the mesh (it passes
    // through the given point, so under an overhang this is the overhang)
    // and that triangle's unit face normal, turned to face the sensor.
    Vec3 contact{};
    Vec3 normal{};
    std::vector<float> indentation_mm;  // height * width, after deformation (>= 0)
    std::vector<uint8_t> image;   // height * width * 3, stored channel order (cv::imwrite-ready)
    int contact_pixels = 0;       // pixels of the contact mask: undeformed indentation > 0 (before the drape)
};

class TouchRenderer {
public:
    // Keeps a copy of the mesh (object units = mm). mm_per_px overrides the
    // calibration's pixel size (a user's own sensor).
    TouchRenderer(const Calibration& calib, const io::TriangleMesh& mesh, std::optional<double> mm_per_px = {});

    // Touch at `point` with outward unit `normal`: sensor z = -normal (tilted
    // per params), gel placed at first contact over the window (+ a margin),
    // pressed params.press_mm. Rejects the touch (ok = false) when the centre
    // ray misses the mesh or the centre is not in contact (other geometry
    // reaches the gel first; note a flat face tilted 8 degrees already
    // reaches the window's corner ~1.7 mm before its centre). A non-finite
    // point or a zero normal is rejected too. `seed` drives the noise only
    // (SplitMix64, Box-Muller): same inputs and seed, same bytes. Throws
    // vtloc::Error for parameters out of range (press_mm outside (0, 20],
    // tilt outside 0..80 degrees, a background of the wrong size).
    Touch render(const Vec3& point, const Vec3& normal, const TouchParams& params, const Appearance& look,
                 uint64_t seed) const;

    // The same touch with the sensor's axes and centre line given directly:
    // pose.R's columns are the sensor x, y, z; pose.t is any point on the
    // centre line (the gel is placed along it as in render()). No rejection:
    // ok is false only when no part of the mesh lies under the window (+ its
    // margin); contact and normal are filled only when the centre ray hits
    // (else they stay zero). The reality check uses it to put a ball's contact
    // away from the sensor centre.
    Touch render_at(const SensorPose& sensor, double press_mm, const Appearance& look, uint64_t seed) const;

    // The Taxim-style drape: Gaussian blur widths (mm) applied in order, the
    // contact region restored after each (see gel_shading.h for the default).
    void set_drape_sigmas_mm(std::vector<double> sigmas_mm);
    const std::vector<double>& drape_sigmas_mm() const;

    // The frame of an undeformed gel with this appearance (no noise): the
    // background a user subtracts.
    std::vector<uint8_t> background_frame(const Appearance& look) const;

    const Calibration& calibration() const;
    double mm_per_px() const;

private:
    struct Impl;
    std::shared_ptr<const Impl> impl_;
    std::vector<double> drape_sigmas_mm_;
};

}  // namespace vtloc::sim
