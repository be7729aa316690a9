#!/usr/bin/env python3
"""PyTorch peer of meshgnn's "Handy++" spiral autoencoder (thesis Table 3.1; the Neural3DMM /
SpiralNet++ reference code layout): the same network, spirals, pooling and unpooling, timed
on this CPU for one training step (forward + L1 + backward + Adam, batch 16) and for encode /
decode of a batch of 16, like `cargo bench --bench spiral_autoencoder`.

The template tensors come from our example, so both sides run the identical graph:

    cargo run --release --example spiral_autoencoder -p meshgnn-models -- --export bench-data
    .venv/bin/python benches/peers/spiral_autoencoder_torch.py [bench-data/spiral_template.safetensors]

Without the file, random spirals / pooling of the same shapes are used (levels
11265, 2828, 714, 181, 47; spiral length 9): the cost depends only on the shapes.

Layers follow SpiralNet++ (Gong et al. 2019): SpiralConv = index_select over the vertex axis,
view (B, V, L*C), Linear; pooling = index_select of the kept vertices; unpooling = index_select
of the 3 barycentric corners and a weighted sum (cheaper on CPU than torch.sparse.mm).
"""
import json
import os
import struct
import sys
import time

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

DTYPES = {"F32": np.float32, "U32": np.uint32, "I64": np.int64}


def read_safetensors(path):
    """Minimal safetensors reader (8-byte header length, JSON header, raw little-endian data)."""
    with open(path, "rb") as f:
        data = f.read()
    n = struct.unpack("<Q", data[:8])[0]
    header = json.loads(data[8:8 + n])
    out = {}
    for name, info in header.items():
        if name == "__metadata__":
            continue
        start, end = info["data_offsets"]
        arr = np.frombuffer(data[8 + n + start:8 + n + end], dtype=DTYPES[info["dtype"]])
        out[name] = arr.reshape(info["shape"])
    return out


def template_from_file(path):
    t = read_safetensors(path)
    levels = 0
    while f"level{levels}.vertices" in t:
        levels += 1
    spirals = [torch.from_numpy(t[f"level{i}.spirals"].astype(np.int64)) for i in range(levels)]
    kept = [torch.from_numpy(t[f"pool{i}.kept"].astype(np.int64)) for i in range(levels - 1)]
    up_idx = [torch.from_numpy(t[f"pool{i}.up_indices"].astype(np.int64)) for i in range(levels - 1)]
    up_w = [torch.from_numpy(t[f"pool{i}.up_weights"].copy()) for i in range(levels - 1)]
    return spirals, kept, up_idx, up_w


def random_template(counts=(11265, 2828, 714, 181, 47), length=9, seed=0):
    g = torch.Generator().manual_seed(seed)
    spirals = [torch.randint(0, v, (v, length), generator=g) for v in counts]
    spirals = [torch.cat([torch.arange(v)[:, None], s[:, 1:]], 1) for v, s in zip(counts, spirals)]
    kept = [torch.randperm(counts[i], generator=g)[:counts[i + 1]] for i in range(len(counts) - 1)]
    up_idx = [torch.randint(0, counts[i + 1], (counts[i], 3), generator=g) for i in range(len(counts) - 1)]
    up_w = [torch.softmax(torch.rand(counts[i], 3, generator=g), 1) for i in range(len(counts) - 1)]
    return spirals, kept, up_idx, up_w


class SpiralConv(nn.Module):
    def __init__(self, cin, cout, spiral):
        super().__init__()
        self.register_buffer("idx", spiral.reshape(-1))
        self.v, self.length = spiral.shape
        self.layer = nn.Linear(cin * self.length, cout)

    def forward(self, x):
        b, v, c = x.shape
        x = torch.index_select(x, 1, self.idx).view(b, v, self.length * c)
        return self.layer(x)


class Unpool(nn.Module):
    def __init__(self, idx, w):
        super().__init__()
        self.register_buffer("idx", idx.reshape(-1))
        self.register_buffer("w", w.reshape(1, -1, 3, 1))
        self.n = idx.shape[0]

    def forward(self, x):
        b, _, c = x.shape
        corners = torch.index_select(x, 1, self.idx).view(b, self.n, 3, c)
        return (corners * self.w).sum(2)


class Autoencoder(nn.Module):
    def __init__(self, spirals, kept, up_idx, up_w, channels=(8, 16, 32, 64), latent=8):
        super().__init__()
        ch = [3] + list(channels)
        n = len(channels)
        self.kept = kept
        self.enc = nn.ModuleList([SpiralConv(ch[i], ch[i + 1], spirals[i]) for i in range(n)])
        self.dec = nn.ModuleList([SpiralConv(ch[i + 1], ch[i], spirals[i]) for i in range(n)])
        self.unpool = nn.ModuleList([Unpool(up_idx[i], up_w[i]) for i in range(n)])
        self.coarse = (kept[n - 1].shape[0], ch[n])
        self.enc_fc = nn.Linear(self.coarse[0] * self.coarse[1], latent)
        self.dec_fc = nn.Linear(latent, self.coarse[0] * self.coarse[1])

    def encode(self, x):
        for conv, kept in zip(self.enc, self.kept):
            x = torch.index_select(F.elu(conv(x)), 1, kept)
        return self.enc_fc(x.reshape(x.shape[0], -1))

    def decode(self, z):
        x = self.dec_fc(z).view(z.shape[0], *self.coarse)
        for i in reversed(range(len(self.dec))):
            x = self.dec[i](self.unpool[i](x))
            if i > 0:
                x = F.elu(x)
        return x


def timed(f, repeats=10):
    f()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else None
    if path and os.path.exists(path):
        spirals, kept, up_idx, up_w = template_from_file(path)
        source = path
    else:
        spirals, kept, up_idx, up_w = random_template()
        source = "random spirals/pooling of the default shapes"
    torch.manual_seed(0)
    model = Autoencoder(spirals, kept, up_idx, up_w)
    v = spirals[0].shape[0]
    x = torch.randn(16, v, 3)
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)

    def step():
        opt.zero_grad()
        loss = F.l1_loss(model.decode(model.encode(x)), x)
        loss.backward()
        opt.step()

    with torch.no_grad():
        z = model.encode(x)
    results = {"train_step_b16": timed(step)}
    with torch.no_grad():
        results["encode_b16"] = timed(lambda: model.encode(x))
        results["decode_b16"] = timed(lambda: model.decode(z))
    print(f"torch {torch.__version__}, {torch.get_num_threads()} threads, template: {source}, "
          f"levels {[s.shape[0] for s in spirals]}")
    for name, t in results.items():
        print(f"{name:16s} {t * 1e3:9.2f} ms  ({16 / t:8.1f} meshes/s)")


if __name__ == "__main__":
    main()
