#pragma once
/// \file The pinhole camera model and the IG ray sets, under the sensor names: they live in
/// kernels (pure geometry), so that the map can back-project depth images without the sensor
/// module.
///
/// Thread-safety: as kernels/pinhole_camera.hpp: plain values and pure functions.

#include "nbv/kernels/pinhole_camera.hpp"

namespace nbv::sensor {

using kernels::PinholeCamera;
using kernels::PixelRay;
using kernels::PixelSampling;
using kernels::pixelRays;
using kernels::rayDirectionsCamera;

}  // namespace nbv::sensor
