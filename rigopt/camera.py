"""The ideal pinhole model: focal lengths, FOVs and intrinsics of an undistorted, centred camera.

Conventions
-----------
Horizontal and vertical FOV in degrees (the unit users type), image sizes in pixels ``(width, height)``,
focal lengths in pixels. The principal point is the image centre. Square pixels: one focal length
serves both axes, so the vertical FOV follows from the aspect ratio.

>>> round(float(focal_from_fov(60.0, 320)), 3)
277.128
"""

from __future__ import annotations

import numpy as np


def focal_from_fov(fov_deg, width_px):
    """Focal length in pixels of a horizontal FOV. fov_deg, width_px : (...,) float -> (...,) float."""
    return np.asarray(width_px, dtype=float) / (2.0 * np.tan(np.deg2rad(np.asarray(fov_deg, dtype=float)) / 2.0))


def fov_from_focal(focal_px, width_px):
    """Horizontal FOV in degrees from a focal length. focal_px, width_px : (...,) float -> (...,) float."""
    return np.rad2deg(2.0 * np.arctan(np.asarray(width_px, dtype=float) / (2.0 * np.asarray(focal_px, dtype=float))))


def vertical_fov(fov_deg, width_px, height_px):
    """Vertical FOV in degrees of a square-pixel pinhole. All inputs (...,) float -> (...,) float."""
    return fov_from_focal(focal_from_fov(fov_deg, width_px), height_px)


def intrinsic_matrix(fov_deg, width_px, height_px):
    """3x3 intrinsic matrix ``K`` of a centred pinhole; maps optical-frame rays to pixels. -> (3, 3) float."""
    f = float(focal_from_fov(fov_deg, width_px))
    return np.array([[f, 0.0, width_px / 2.0], [0.0, f, height_px / 2.0], [0.0, 0.0, 1.0]])
