"""Writes the references of meshtrace's view transforms, made by Blender's colour management:
`tests/data/view_transforms/input.exr` and, for each of Blender's views Standard, Filmic and
AgX, `{view}8.png` and `{view}16.png`, that image saved by Blender as a render is saved.

Run with Blender 5 as a Python module (`pip install bpy==5.0.1`, Python 3.11):

    python tools/view_transforms.py tests/data/view_transforms

The input is a 64 × 64 premultiplied RGBA float image: rows from 2^-14 to 2^14 (28 stops,
more than either view's range), columns of grey, 24 saturated hues, 24 half-saturated hues,
and 8 columns of an orange at alpha 1/8 to 1. `Image.save_render` applies the scene's
view transform and display (sRGB) as a render's output does (without its dither, which
meshtrace does not add).
"""

import colorsys
import sys
from pathlib import Path

import bpy

SIZE = 64


def ramp():
    pixels = []
    for y in range(SIZE):
        scale = 2.0 ** (-14 + 28 * y / (SIZE - 1))
        for x in range(SIZE):
            alpha = 1.0
            if x < 8:
                rgb = (1.0, 1.0, 1.0)
            elif x < 56:
                saturation = 1.0 if x < 32 else 0.5
                rgb = colorsys.hsv_to_rgb(((x - 8) % 24) / 24, saturation, 1.0)
            else:
                alpha = (x - 55) / 8
                rgb = (alpha, 0.4 * alpha, 0.1 * alpha)
            pixels += [c * scale for c in rgb] + [alpha]
    image = bpy.data.images.new("ramp", SIZE, SIZE, alpha=True, float_buffer=True)
    image.pixels[:] = pixels
    return image


def main():
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    image = ramp()
    scene = bpy.context.scene
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_depth = "32"
    settings.color_mode = "RGBA"
    image.save_render(str(out / "input.exr"), scene=scene)
    settings.file_format = "PNG"
    for view in ("Standard", "Filmic", "AgX"):
        scene.view_settings.view_transform = view
        for depth in ("8", "16"):
            settings.color_depth = depth
            image.save_render(str(out / f"{view.lower()}{depth}.png"), scene=scene)
    print(f"{out}: input.exr and 6 PNGs, Blender {bpy.app.version_string}")


if __name__ == "__main__":
    main()
