#!/usr/bin/env python3
"""A tileable ambient-occlusion texture and a bent-normal map from a height image, as a texture artist
bakes them: image in (OpenImageIO), hfbake.p1 on a repeat field, 16-bit PNGs out.

    texture_from_image.py HEIGHT.png OUT_PREFIX [--height-scale S] [--directions K]

Writes OUT_PREFIX_ao.png (16-bit grey, ao) and OUT_PREFIX_bent_normal.png (16-bit RGB, 0.5 + 0.5 n). The
heights are the image's first channel as stored (an integer image's integers, as `hfbake bake` reads them:
docs/heights.md) times --height-scale, in texels: a 16-bit map spanning H texels of height takes H / 65535.

Inside Blender the image comes from bpy instead of OpenImageIO:

    image = bpy.data.images["height"]
    pixels = np.empty(len(image.pixels), np.float32)
    image.pixels.foreach_get(pixels)
    heights = pixels.reshape(image.size[1], image.size[0], image.channels)[::-1, :, 0].copy()
"""
import argparse

import numpy as np
import OpenImageIO as oiio

import hfbake


def write_png16(path, values):
    """0..1 floats as a 16-bit PNG (rounded to the nearest of 65536 levels)."""
    levels = np.round(np.clip(values, 0.0, 1.0) * 65535.0).astype(np.uint16)
    if levels.ndim == 2:
        levels = levels[:, :, np.newaxis]
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(levels.shape[1], levels.shape[0], levels.shape[2], "uint16"))
    out.write_image(np.ascontiguousarray(levels))
    out.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("image")
    parser.add_argument("out_prefix")
    parser.add_argument("--height-scale", type=float, default=16.0)
    parser.add_argument("--directions", type=int, default=32)
    args = parser.parse_args()

    inp = oiio.ImageInput.open(args.image)
    if inp is None:
        raise SystemExit(oiio.geterror())
    spec = inp.spec()
    stored = inp.read_image(spec.format)  # integers as stored, not scaled to 0..1
    heights = np.asarray(stored).reshape(spec.height, spec.width, spec.nchannels)[:, :, 0].astype(np.float32)
    inp.close()

    layers = hfbake.p1(heights, height_scale=args.height_scale, wrap="repeat", directions=args.directions,
                       layers=["ao", "bent_normal"])
    write_png16(f"{args.out_prefix}_ao.png", layers["ao"])
    write_png16(f"{args.out_prefix}_bent_normal.png", 0.5 + 0.5 * layers["bent_normal"])


if __name__ == "__main__":
    main()
