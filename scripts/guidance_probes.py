#!/usr/bin/python3
"""Two probes of how guidance acts inside a flow planner's Euler sampler, on
exported planners (`flowplan export`; inpainting, no splitting needed). Both
use the collision term's gradient alone (the other terms' weights set to 0).

survival   A fixed push d on the interior states (normalized units) is added
           after Euler step i only (i = 0 .. N-1, reaching flow time t_{i+1},
           where a guidance step acts), and the plan is finished unguided.
           The push's survival is <x1(pushed) - x1, d> / <d, d>: 1 if the rest
           of the sampling keeps it, 0 if the flow undoes it; after the last
           step it is 1 by definition. d is minus the collision gradient at
           the unguided plan (guide.gradient), scaled per plan to an RMS of
           --push over the interior.
direction  At the states where guidance acts, x_{t_{i+1}} after each Euler
           step, the cosine between the collision gradient at the final plan
           and the gradient at x_t (what the guidance step uses) or at the
           clean-sample prediction x1_hat = x_t + (1 - t) v (inpainted). At
           t = 1 both are the plan: cosine 1.

    /usr/bin/python3 scripts/guidance_probes.py [LABEL=]PLANNER.pt ... \
        --plans 64 --json probes.json [--plot probes.png]

The scene is the paper's sphere (0.5, 0, 0.2), radius --radius; start and goal
TCPs (0.5, -/+0.3, 0.2), gripper down. Plans whose final collision gradient is
zero (clear of the sphere by more than the margin) have no direction and are
left out of both probes; how many were used is reported. Two self-checks are
written beside the figures: the probe's unguided plans against the planner's
own plan(..., scale=0), and its x1_hat against the sampler's integrate() of
one step to t = 1 (largest absolute differences).
"""
import argparse
import json
import sys

import torch


def euler(sampler, x, s, g, t0, steps, h):
    """Unguided Euler steps of size h from flow time t0, inpainting after each: x (B, T, D) normalized."""
    for k in range(steps):
        t = torch.full([x.size(0)], t0 + k * h)
        x = x + h * sampler.velocity(x, t, s, g)
        x = torch.cat([s.unsqueeze(1), x[:, 1:-1], g.unsqueeze(1)], 1)
    return x


def cosine(a, b):
    """Row-wise cosine (B,) of a, b (B, T, D) over their interior states."""
    a, b = a[:, 1:-1].flatten(1), b[:, 1:-1].flatten(1)
    return (a * b).sum(1) / (a.norm(dim=1) * b.norm(dim=1)).clamp_min(1e-30)


def probe(path, plans, radius, push, seed):
    planner = torch.jit.load(path)
    sampler = planner.sampler
    if sampler.conditioning != "inpaint":
        sys.exit(f"{path}: the probes need an inpainting planner, got {sampler.conditioning}")
    opts = dict(planner.settings)
    for key in ("guidance.smoothness_weight", "guidance.joint_limit_weight", "guidance.joint_speed_weight",
                "guidance.user_cost_weight"):
        if key in opts:
            opts[key] = 0.0  # the collision term alone
    steps = int(opts["sampler.steps"])
    h = 1.0 / steps
    scene = {"spheres": torch.tensor([[0.5, 0.0, 0.2, radius]])}
    ends = planner.ik(torch.tensor([[0.5, -0.3, 0.2], [0.5, 0.3, 0.2]], dtype=torch.float64)).float()  # (2, J)
    J = ends.size(1)
    D = sampler.normalizer.normalize(torch.zeros(1, 2 * J)).size(1)
    start = torch.cat([ends[0:1], torch.zeros(1, D - J)], 1).expand(plans, D)  # (B, D) raw
    goal = torch.cat([ends[1:2], torch.zeros(1, D - J)], 1).expand(plans, D)
    s, g = sampler.normalizer.normalize(start), sampler.normalizer.normalize(goal)  # (B, D) normalized
    torch.manual_seed(seed)
    noise = torch.randn(plans, sampler.horizon, D)
    inpaint = lambda x: torch.cat([s.unsqueeze(1), x[:, 1:-1], g.unsqueeze(1)], 1)
    with torch.no_grad():
        # The unguided trajectory x_{t_i}, i = 0 .. N.
        xs = [inpaint(noise)]
        for i in range(steps):
            xs.append(euler(sampler, xs[-1], s, g, i * h, 1, h))
        final = xs[-1]
        own = planner.plan(start, goal, noise, scale=0.0)  # (B, T, D) raw
        check_plan = (sampler.normalizer.denormalize(final) - own)[:, 1:-1].abs().max().item()
        grad_final = sampler.guide.gradient(final, scene, opts)  # (B, T, D)
        used = grad_final[:, 1:-1].flatten(1).norm(dim=1) > 0  # plans with a direction
        n = int(used.sum())
        result = {"planner": path.rsplit("/", 1)[-1], "plans": plans, "plans_used": n, "radius": radius,
                  "steps": steps, "push_rms": push, "t": [(i + 1) * h for i in range(steps)],
                  "check_unguided_plan_max_abs": check_plan}
        if n == 0:
            return result
        d = -grad_final
        d[:, 0] = 0.0
        d[:, -1] = 0.0
        rms = d[:, 1:-1].flatten(1).pow(2).mean(1).sqrt().clamp_min(1e-30)
        d = d * (push / rms).view(-1, 1, 1)
        survival, at_xt, at_x1hat = [], [], []
        check_x1hat = 0.0
        choices = {"guidance.schedule": planner.schedule, "sampler.guide_at": planner.guide_at}
        for i in range(steps):
            t = (i + 1) * h
            pushed = euler(sampler, xs[i + 1] + d, s, g, t, steps - 1 - i, h)
            change = (pushed - final)[:, 1:-1].flatten(1)
            share = (change * d[:, 1:-1].flatten(1)).sum(1) / d[:, 1:-1].flatten(1).pow(2).sum(1)
            survival.append(share[used].tolist())
            x = xs[i + 1]
            if i + 1 < steps:
                x1_hat = inpaint(x + (1.0 - t) * sampler.velocity(x, torch.full([plans], t), s, g))
                one_step = sampler.integrate(x, s, g, t, 1, {}, opts, choices, False)
                check_x1hat = max(check_x1hat, (x1_hat - one_step).abs().max().item())
            else:
                x1_hat = x
            at_xt.append(cosine(sampler.guide.gradient(x, scene, opts), grad_final)[used].tolist())
            at_x1hat.append(cosine(sampler.guide.gradient(x1_hat, scene, opts), grad_final)[used].tolist())
    median = lambda rows: [float(torch.tensor(r).median()) for r in rows]
    quartiles = lambda rows: [[float(torch.tensor(r).quantile(0.25)), float(torch.tensor(r).quantile(0.75))] for r in rows]
    result.update({"survival_median": median(survival), "survival_quartiles": quartiles(survival),
                   "cos_xt_median": median(at_xt), "cos_xt_quartiles": quartiles(at_xt),
                   "cos_x1hat_median": median(at_x1hat), "cos_x1hat_quartiles": quartiles(at_x1hat),
                   "check_x1hat_max_abs": check_x1hat})
    return result


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8))
    for r in results:
        if r["plans_used"] == 0:
            continue
        label = r.get("label", r["planner"])
        a.plot(r["t"], r["survival_median"], marker="o", label=label)
        line, = b.plot(r["t"], r["cos_x1hat_median"], marker="o", label=label + ", at x1_hat")
        b.plot(r["t"], r["cos_xt_median"], marker="x", linestyle="--", color=line.get_color(),
               label=label + ", at x_t")
    a.set(xlabel="flow time t after the pushed step", ylabel="share of the push in the plan (median)",
          title="survival of a push")
    b.set(xlabel="flow time t of the guided state", ylabel="cosine with the gradient at the plan (median)",
          title="direction of the cost gradient")
    for ax in (a, b):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("planners", nargs="+", help="exported planners (.pt), optionally LABEL=PATH")
    parser.add_argument("--plans", type=int, default=64)
    parser.add_argument("--radius", type=float, default=0.1, help="the sphere's radius (m)")
    parser.add_argument("--push", type=float, default=0.01, help="RMS of the push over the interior (normalized units)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--json", required=True)
    parser.add_argument("--plot")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    results = []
    for spec in args.planners:
        label, _, path = spec.rpartition("=")
        # The executor's optimisations off, as flowplan plans: with them on, the first calls of each of
        # the planner's methods spend seconds profiling and the probes call many methods a few times.
        with torch.jit.optimized_execution(False):
            r = probe(path, args.plans, args.radius, args.push, args.seed)
        r["label"] = label or path
        results.append(r)
        if r["plans_used"] == 0:
            print(f"{r['label']}: no plan comes within the collision margin; nothing to probe")
            continue
        print(f"{r['label']}: {r['plans_used']} of {r['plans']} plans within the collision margin; self-checks "
              f"{r['check_unguided_plan_max_abs']:.1e} (unguided plan), {r['check_x1hat_max_abs']:.1e} (x1_hat)")
        print("  t                " + " ".join(f"{t:6.2f}" for t in r["t"]))
        print("  survival         " + " ".join(f"{v:6.3f}" for v in r["survival_median"]))
        print("  cos at x_t       " + " ".join(f"{v:6.3f}" for v in r["cos_xt_median"]))
        print("  cos at x1_hat    " + " ".join(f"{v:6.3f}" for v in r["cos_x1hat_median"]))
    with open(args.json, "w") as f:
        json.dump(results, f, indent=1)
    if args.plot:
        plot(results, args.plot)
    return 0


if __name__ == "__main__":
    sys.exit(main())
