#!/usr/bin/python3
"""Turns an exported planner of format 5 (a UNet planner of any objective) back
into a checkpoint that `flowplan export` exports again with today's code, and
checks the new file against the old one. An exported file carries its sampler,
guidance and kinematics code as it was when it was written; this is how a
shipped file takes up later changes of that code with its weights unchanged.

    build/bench/speed_bench --out /tmp/template --repeats 1   # fresh_franka.pt (flow) and fresh_franka_mpd.pt (DDPM)
    /usr/bin/python3 pretrained/convert_format5.py OLD.pt /tmp/template/fresh_franka_mpd.pt CONVERTED.pt
    build/apps/flowplan/flowplan export --ckpt CONVERTED.pt --out NEW.pt
    /usr/bin/python3 pretrained/convert_format5.py --check OLD.pt NEW.pt

The template is any checkpoint of the same network and objective; its weights
(online and EMA alike: an exported file holds only the EMA weights) are
replaced by the old file's, undoing the export's one change to them (the FiLM
layers of every residual block stacked into one product), and its normalizer,
config, robot, environment, time step, horizon and state labels by the old
file's. The check plans with the same noise from both
files, unguided and guided around a sphere with the old file's settings, and
requires agreement to 1e-5 unguided and 1e-4 guided (the guidance code of a
newer file may compute the same gradients in another order, and a guided
DDPM chain carries that rounding through its 24 steps: 6.8e-5 for the shipped
MPD planner).
"""
import re
import sys

import torch

import convert_format3  # its command line, shared

NETWORK = "sampler.network."


def block_order(name):
    """The export's order of residual blocks: down levels, the middle, up levels (models/unet1d.cc)."""
    m = re.match(r"(down|mid|up)(\d+)(?:_block(\d+))?$", name)
    if m is None:
        sys.exit(f"unexpected residual block name {name}")
    return ({"down": 0, "mid": 1, "up": 2}[m.group(1)], int(m.group(2)), int(m.group(3) or 0))


def convert(old_path, template_path, out_path, step):
    old = torch.jit.load(old_path)
    if getattr(old, "format_version", None) != 5:
        sys.exit(f"{old_path}: expected an exported planner of format 5, got format {old.format_version}")
    ckpt = torch.jit.load(template_path)
    weights = {name[len(NETWORK):]: t for name, t in list(old.named_parameters()) + list(old.named_buffers())
               if name.startswith(NETWORK)}
    if "p_films_weight" not in weights:
        sys.exit(f"{old_path}: not a UNet planner (no stacked FiLM layers)")
    with torch.no_grad():
        for part in (ckpt.model, ckpt.ema):
            tensors = dict(part.named_parameters())
            tensors.update(dict(part.named_buffers()))
            blocks = sorted({name.rsplit(".film.", 1)[0] for name in tensors if ".film." in name}, key=block_order)
            row = 0
            for block in blocks:
                weight, bias = tensors[block + ".film.weight"], tensors[block + ".film.bias"]
                weight.copy_(weights["p_films_weight"][row:row + weight.size(0)])
                bias.copy_(weights["p_films_bias"][row:row + weight.size(0)])
                row += weight.size(0)
            if row != weights["p_films_weight"].size(0):
                sys.exit(f"{template_path}: its FiLM layers have {row} rows, {old_path}'s {weights['p_films_weight'].size(0)}")
            copied = 2
            for name, tensor in tensors.items():
                if ".film." in name:
                    continue
                key = "p_" + name.replace(".", "_")
                if key not in weights or weights[key].shape != tensor.shape:
                    sys.exit(f"{template_path}: {name} {tuple(tensor.shape)} has no match in {old_path}")
                tensor.copy_(weights[key])
                copied += 1
            if copied != len(weights):
                sys.exit(f"{template_path}: {copied} tensors, {old_path} has {len(weights)}: another network")
    ckpt.normalizer_lo = old.normalizer.lo.clone()
    ckpt.normalizer_hi = old.normalizer.hi.clone()
    ckpt.step = step
    ckpt.config = old.config
    ckpt.robot = old.robot_description
    ckpt.env = old.env
    ckpt.dt = old.dt
    ckpt.horizon = old.horizon
    ckpt.state_labels = old.state_labels
    ckpt.data_fingerprint = "converted from " + old_path
    torch.jit.save(ckpt, out_path)
    print(f"wrote {out_path}: the network, normalizer and config of {old_path}, step {step}")


def check(old_path, new_path):
    torch.set_num_threads(2)
    old, new = torch.jit.load(old_path), torch.jit.load(new_path)
    gen = torch.Generator().manual_seed(0)
    B = 16
    with torch.no_grad():
        start_q = old.ik(torch.tensor([[0.5, -0.3, 0.2]]).double()).float()
        goal_q = old.ik(torch.tensor([[0.5, 0.3, 0.2]]).double()).float()
        start = torch.cat([start_q, torch.zeros_like(start_q)], 1).expand(B, -1)
        goal = torch.cat([goal_q, torch.zeros_like(goal_q)], 1).expand(B, -1)
        noise = torch.randn([B] + list(old.noise_shape), generator=gen)
        renoise = torch.randn([B] + list(old.renoise_shape), generator=gen) if len(old.renoise_shape) > 0 else None
        sphere = torch.tensor([[0.5, 0.0, 0.2, 0.1]])
        settings = dict(old.settings)  # the old file's defaults, whatever the new one's are
        failed = []
        for name, old_plan, new_plan, tolerance in [
            ("unguided", old.plan(start, goal, noise, renoise, scale=0.0),
             new.plan(start, goal, noise, renoise, scale=0.0), 1e-5),
            ("guided", old.plan(start, goal, noise, renoise, spheres=sphere),
             new.plan(start, goal, noise, renoise, spheres=sphere, settings=settings), 1e-4),
        ]:
            error = (old_plan - new_plan).abs().max().item()
            print(f"{name}: largest difference {error:.2e} over {B} plans (at most {tolerance:g})")
            if error > tolerance:
                failed.append(f"{name} {error:.2e}")
    if failed:
        sys.exit(f"{new_path} does not plan as {old_path} does: " + ", ".join(failed))


if __name__ == "__main__":
    convert_format3.main(__doc__, convert, check)
