"""The benchmark's fixed camera numbers, owned once: the image size of its cameras and of the synthetic renderer.

Plain data (no imports), at the bottom layer, so that every layer (the camera model, rig files, the designer's
defaults shown in ``--help``) reads the same value.
"""

#: (width, height) px: the image size of every camera of the benchmark's rigs (CARLA's sensors, the ideal
#: pinhole a rig file's ``fov`` describes when it gives no ``image_size``).
BENCHMARK_IMAGE_SIZE = (1280, 720)

#: (width, height) px: the synthetic benchmark's default rendering size (``rigopt bench generate --size``), the
#: benchmark's 16:9 at an eighth of its width.
SYNTHETIC_IMAGE_SIZE = (160, 90)

#: Largest image side (px) of any camera: beyond every camera made (the largest automotive sensors are under
#: 4000 px, industrial ones under 15000), so a larger number is a typo or a unit mistake.
MAX_IMAGE_SIDE = 20000
