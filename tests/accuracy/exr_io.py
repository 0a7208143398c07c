"""One-channel float EXRs for the accuracy scripts: a field written for a job, a layer's channel read back."""
import numpy as np
import OpenImageIO as oiio


def write_exr(path, z):
    """z (rows, columns) as a float EXR of one channel, Y."""
    out = oiio.ImageOutput.create(path)
    spec = oiio.ImageSpec(z.shape[1], z.shape[0], 1, "float")
    spec.channelnames = ("Y",)
    out.open(path, spec)
    out.write_image(np.ascontiguousarray(z.reshape(z.shape[0], z.shape[1], 1), dtype=np.float32))
    out.close()


def read_channel(path, name):
    """The channel `name` ("indirect.R", "obscurance.Y") of an EXR as a (rows, columns) array."""
    inp = oiio.ImageInput.open(path)
    spec = inp.spec()
    px = np.asarray(inp.read_image(0, 0, 0, spec.nchannels, "float"))
    inp.close()
    return px.reshape(spec.height, spec.width, spec.nchannels)[:, :, list(spec.channelnames).index(name)]
