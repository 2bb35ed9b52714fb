"""A render against its reference per 4 x 4-pixel block (bench/spray_light_bench.py, bench/skier_light_bench.py)."""

import numpy as np

BLOCK = 4  # pixels


def blocks(values, shape):
    rows, columns = shape
    return values.reshape(rows // BLOCK, BLOCK, columns // BLOCK, BLOCK).sum((1, 3))


def compare(label, baked, reference, shape, width=28):
    """Per 4 x 4-pixel block: mean |relative error|, worst, and the bias of the sum, over blocks with light."""
    b, m = blocks(baked.mean(1), shape), blocks(reference.mean(1), shape)
    lit = m > 0.05 * m.max()
    error = (b[lit] - m[lit]) / m[lit]
    bias = b[lit].sum() / m[lit].sum() - 1
    print(f"  {label:<{width}} {lit.sum():4d} blocks  mean |err| {100 * np.abs(error).mean():5.1f} %  "
          f"worst {100 * error[np.argmax(np.abs(error))]:+6.1f} %  bias {100 * bias:+5.1f} %", flush=True)
