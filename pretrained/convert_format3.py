#!/usr/bin/python3
"""Turns an exported planner of format 3 (a UNet flow-matching planner) into a
checkpoint that `flowplan export` re-exports in today's format, and checks the
re-exported file against the old one.

    build/bench/speed_bench --out /tmp/template --repeats 1   # writes /tmp/template/fresh_franka.pt
    /usr/bin/python3 pretrained/convert_format3.py OLD.pt /tmp/template/fresh_franka.pt CONVERTED.pt
    build/apps/flowplan/flowplan export --ckpt CONVERTED.pt --out NEW.pt
    /usr/bin/python3 pretrained/convert_format3.py --check OLD.pt NEW.pt

The template is any checkpoint of the same network (the reach preset's UNet);
its weights are replaced by the old file's (online and EMA weights alike: a
format-3 file holds only the EMA weights), its normalizer, config, robot and
trajectory by the old file's. The check plans with the same noise around a
sphere from both files, unguided and guided, and requires agreement to 1e-5.
"""
import argparse
import sys

import torch


def convert(old_path, template_path, out_path, step):
    old = torch.jit.load(old_path)
    if old.format_version != 3 or old.planner != "flow_matching":
        sys.exit(f"{old_path}: expected a format-3 flow-matching planner, got format {old.format_version}, {old.planner}")
    ckpt = torch.jit.load(template_path)
    weights = dict(old.named_buffers())
    with torch.no_grad():
        for part in (ckpt.model, ckpt.ema):
            tensors = dict(part.named_parameters())
            tensors.update(dict(part.named_buffers()))
            for name, tensor in tensors.items():
                key = "p_" + name.replace(".", "_")
                if key not in weights or weights[key].shape != tensor.shape:
                    sys.exit(f"{template_path}: {name} {tuple(tensor.shape)} has no match in {old_path}")
                tensor.copy_(weights[key])
            if len(tensors) != sum(1 for k in weights if k.startswith("p_")):
                sys.exit(f"{template_path}: {len(tensors)} tensors, {old_path} has another network")
    ckpt.normalizer_lo = old.lo.clone()
    ckpt.normalizer_hi = old.hi.clone()
    ckpt.step = step
    ckpt.config = old.config
    ckpt.robot = old.robot
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
    B, T, D = 16, old.horizon, old.state_dim
    with torch.no_grad():
        start_q = old.ik(torch.tensor([[0.5, -0.3, 0.2]]).double()).float()
        goal_q = old.ik(torch.tensor([[0.5, 0.3, 0.2]]).double()).float()
        start = torch.cat([start_q, torch.zeros_like(start_q)], 1).expand(B, D)
        goal = torch.cat([goal_q, torch.zeros_like(goal_q)], 1).expand(B, D)
        noise = torch.randn(B, T, D, generator=gen)
        sphere = torch.tensor([[0.5, 0.0, 0.2, 0.1]])
        worst = 0.0
        for name, old_plan, new_plan in [
            ("unguided", old.plan(start, goal, noise, None, None, 0.0), new.plan(start, goal, noise, scale=0.0)),
            # the format-3 sampler had no end-game: compare without the one the new file may default to
            ("guided", old.plan(start, goal, noise, None, sphere),
             new.plan(start, goal, noise, spheres=sphere, settings={"sampler.final_iterations": 0.0})),
        ]:
            error = (old_plan - new_plan).abs().max().item()
            print(f"{name}: largest difference {error:.2e} over {B} plans")
            worst = max(worst, error)
    if worst > 1e-5:
        sys.exit(f"{new_path} does not plan as {old_path} does (largest difference {worst:.2e})")


def main(doc=__doc__, convert_file=convert, check_files=check):
    """The command line of this script and of convert_format5.py: DOC, and their own convert and check."""
    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--check", action="store_true", help="compare OLD.pt and NEW.pt instead of converting")
    parser.add_argument("--step", type=int, default=10000, help="the training step to record")
    parser.add_argument("files", nargs="+")
    args = parser.parse_args()
    if args.check:
        if len(args.files) != 2:
            parser.error("--check takes OLD.pt NEW.pt")
        check_files(*args.files)
    else:
        if len(args.files) != 3:
            parser.error("expected OLD.pt TEMPLATE_CHECKPOINT.pt OUT.pt")
        convert_file(*args.files, args.step)


if __name__ == "__main__":
    main()
