"""Times torch's u_net(1, 1) shape (phiml's: DoubleConv, 2x max-pool, bilinear 2x, concat, 1x1
conv) for forward + backward of sum(gy * f(x)) at batch 128 on 64x64, as conv_net_bench does.

Usage: python3 unet_torch.py THREADS REPEATS  ->  lines "torch_<dtype>_bn<0|1> <ms per call>".
"""
import sys
import time

import torch
from torch import nn


def double_conv(cin, cout, bn):
    layers = []
    for c in (cin, cout):
        layers.append(nn.Conv2d(c, cout, 3, padding=1))
        if bn:
            layers.append(nn.BatchNorm2d(cout))
        layers.append(nn.ReLU())
    return nn.Sequential(*layers)


class UNet(nn.Module):
    def __init__(self, levels=4, filters=16, bn=False):
        super().__init__()
        self.inc = double_conv(1, filters, bn)
        self.down = nn.ModuleList(double_conv(filters, filters, bn) for _ in range(levels - 1))
        self.up = nn.ModuleList(double_conv(2 * filters, filters, bn) for _ in range(levels - 1))
        self.outc = nn.Conv2d(filters, 1, 1)

    def forward(self, x):
        skips = [self.inc(x)]
        for block in self.down:
            skips.append(block(nn.functional.max_pool2d(skips[-1], 2)))
        y = skips.pop()
        for block in self.up:
            y = nn.functional.interpolate(y, scale_factor=2, mode="bilinear", align_corners=False)
            y = block(torch.cat([skips.pop(), y], dim=1))
        return self.outc(y)


def main():
    threads, repeats = int(sys.argv[1]), int(sys.argv[2])
    torch.set_num_threads(threads)
    torch.manual_seed(0)
    for dtype, label in ((torch.float64, "f64"), (torch.float32, "f32")):
        for bn in (False, True):
            net = UNet(bn=bn).to(dtype)
            x = torch.rand(128, 1, 64, 64, dtype=dtype)
            gy = torch.rand(128, 1, 64, 64, dtype=dtype)
            best = float("inf")
            for _ in range(repeats + 1):  # the first call warms up
                net.zero_grad()
                start = time.perf_counter()
                (net(x) * gy).sum().backward()
                best = min(best, time.perf_counter() - start)
            print(f"torch_{label}_bn{int(bn)} {best * 1e3:.1f}", flush=True)


if __name__ == "__main__":
    main()
