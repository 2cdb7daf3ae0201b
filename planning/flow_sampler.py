# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# FlowSampler, the flow planner's sampler (SPEC section 2): Euler steps of the
# network's velocity from noise (t = 0) to a plan (t = 1), inpainting or
# direct conditioning, guidance, and optional midpoint splitting. Submodules
# network (forward(x, t, cond)), normalizer and guide; attributes conditioning
# ("inpaint" or "direct"), splitting ("none" or "midpoint"), horizon (T).
# Settings: sampler.steps, sampler.split_time, the guidance variants
# sampler.guide_from, .prediction_iterations, .final_iterations,
# .final_denoise_time, .final_spread, .final_joint_speed_weight,
# .midpoint_iterations, and the guide's; choices
# "guidance.schedule" and "sampler.guide_at" (docs/planning.md, "Guidance
# variants").

from typing import Dict, Optional

import torch
from torch import Tensor

from flowplan.script.models.conditioning import condition_vector
from flowplan.script.guidance.guidance import schedule_factor
from flowplan.script.planning.sampling import conditioned, guide_targets, setting_int, split_steps, spread_matrix


class FlowSampler:
    def velocity(self, x: Tensor, t: Tensor, start: Tensor, goal: Tensor) -> Tensor:
        """The network's velocity (B, T', D) at normalized x (B, T', D), flow time
        t (B,), with the boundary conditions start, goal (B, D) normalized."""
        inpainting = self.conditioning == "inpaint"
        return self.network.forward(conditioned(x, start, goal, inpainting), t, condition_vector(start, goal, inpainting))

    def descend(self, x: Tensor, factor: float, iterations: int, start: Tensor, goal: Tensor,
                scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tensor:
        """`iterations` guidance steps x <- x - factor * gradient(x) on normalized
        plans x (B, T', D), the ends re-imposed after each."""
        inpainting = self.conditioning == "inpaint"
        for g in range(iterations):
            x = conditioned(x - factor * self.guide.gradient(x, scene, opts), start, goal, inpainting)
        return x

    def integrate(self, x: Tensor, start: Tensor, goal: Tensor, t0: float, steps: int,
                  scene: Dict[str, Tensor], opts: Dict[str, float], choices: Dict[str, str], guided: bool) -> Tensor:
        """Euler from flow time t0 to 1 in `steps` steps of h, guided as
        sampler.guide_at says, from flow time sampler.guide_from on:
          state:      x <- x + h v(x, t_i); x <- x - s b(t_{i+1}) g(x)
          velocity:   x̂1 = x + (1 - t_i) v; x <- x + h (v - s b(t_i) g(x̂1))
          prediction: x̂1 moved by G steps x̂1 <- x̂1 - s b(t_i) g(x̂1); x <- x + h (x̂1 - x) / (1 - t_i)
        (g the guide's gradient, the ends re-imposed after each step; with the
        `ratio` schedule b(0) = 1000 in the velocity and prediction forms), then the
        end-game (end_game)."""
        inpainting = self.conditioning == "inpaint"
        at = choices["sampler.guide_at"]
        schedule = choices["guidance.schedule"]
        scale = opts["guidance.scale"]
        guide_from = opts["sampler.guide_from"]
        x = conditioned(x, start, goal, inpainting)
        h = (1.0 - t0) / steps
        for i in range(steps):
            t_i = t0 + i * h
            t = torch.full([x.size(0)], t_i, dtype=x.dtype, device=x.device)
            v = self.velocity(x, t, start, goal)
            if guided and at != "state" and t_i >= guide_from - 1e-9:
                predicted = conditioned(x + (1.0 - t_i) * v, start, goal, inpainting)
                factor = scale * schedule_factor(schedule, t_i)
                if at == "velocity":
                    v = v - factor * self.guide.gradient(predicted, scene, opts)
                else:
                    moved = self.descend(predicted, factor, setting_int(opts, "sampler.prediction_iterations"),
                                         start, goal, scene, opts)
                    v = v + (moved - predicted) / (1.0 - t_i)
            x = x + h * v
            if guided and at == "state" and t_i + h >= guide_from - 1e-9:
                x = self.guide.step(x, t_i + h, scene, opts, schedule)
            x = conditioned(x, start, goal, inpainting)
        if guided:
            x = self.end_game(x, start, goal, scene, opts)
        return x

    def end_game(self, x: Tensor, start: Tensor, goal: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tensor:
        """sampler.final_iterations steps x <- x - s M g(x) on finished normalized
        plans x (B, T', D): g the guide's gradient with the joint-speed term's
        weight raised by sampler.final_joint_speed_weight, M the identity or, with
        sampler.final_spread = l > 0, the spread of each state's push over its
        neighbours (spread_matrix; the end states stay, under direct conditioning
        too, where a plain step moves them); the ends re-imposed after
        each step, then an Euler step from sampler.final_denoise_time to 1 when
        that is non-zero."""
        iterations = setting_int(opts, "sampler.final_iterations")
        if iterations == 0:
            return x
        inpainting = self.conditioning == "inpaint"
        scale = opts["guidance.scale"]
        denoise_time = opts["sampler.final_denoise_time"]
        end_opts: Dict[str, float] = {}
        for key, value in opts.items():
            end_opts[key] = value
        end_opts["guidance.joint_speed_weight"] = opts["guidance.joint_speed_weight"] + opts["sampler.final_joint_speed_weight"]
        length = opts["sampler.final_spread"]
        spread = spread_matrix(x.size(1), length, x) if length > 0.0 else None
        for g in range(iterations):
            push = self.guide.gradient(x, scene, end_opts)
            if spread is not None:
                push = torch.matmul(spread, push)
            x = conditioned(x - scale * push, start, goal, inpainting)
            if denoise_time > 0.0:
                t_r = torch.full([x.size(0)], denoise_time, dtype=x.dtype, device=x.device)
                x = conditioned(x + (1.0 - denoise_time) * self.velocity(x, t_r, start, goal), start, goal, inpainting)
        return x

    def sample_normalized(self, start: Tensor, goal: Tensor, noise: Tensor, renoise: Optional[Tensor],
                          scene: Dict[str, Tensor], opts: Dict[str, float], choices: Dict[str, str]) -> Tensor:
        """start, goal (B, D) normalized; noise, renoise (B, T, D) standard normal
        -> plans (B, T, D) normalized, unclamped."""
        at = choices["sampler.guide_at"]
        assert at in guide_targets(), "plan: guide_at (sampler.guide_at): expected one of " + ", ".join(guide_targets()) + ", got " + at
        guided = self.guide.active(scene, opts)
        steps = setting_int(opts, "sampler.steps")
        assert steps >= 1, "plan: settings: sampler.steps: expected at least one step, got " + str(steps)
        assert opts["sampler.final_denoise_time"] < 1.0, "plan: settings: sampler.final_denoise_time: expected a flow time below 1, got " + str(opts["sampler.final_denoise_time"])
        assert opts["sampler.guide_from"] <= 1.0, "plan: settings: sampler.guide_from: expected a flow time of at most 1, got " + str(opts["sampler.guide_from"])
        assert setting_int(opts, "sampler.prediction_iterations") >= 1, "plan: settings: sampler.prediction_iterations: expected at least one step, got " + str(opts["sampler.prediction_iterations"])
        split_time = opts["sampler.split_time"]
        assert split_time > 0.0 and split_time < 1.0, "plan: settings: sampler.split_time: expected a flow time in (0, 1), got " + str(split_time)
        x = self.integrate(noise, start, goal, 0.0, steps, scene, opts, choices, guided)
        if self.splitting == "none":
            return x
        assert renoise is not None, "plan: renoise: this planner splits trajectories and needs re-noising noise"
        if guided:
            x = self.descend(x, opts["guidance.scale"], setting_int(opts, "sampler.midpoint_iterations"), start, goal,
                             scene, opts)
        # Midpoint splitting: the states on either side of the middle become the
        # boundaries of the two halves, so the joined plan has no duplicate state.
        B = x.size(0)
        half = self.horizon // 2
        before_mid = x[:, half - 1]
        after_mid = x[:, half]
        x = (1.0 - split_time) * renoise + split_time * x
        halves = torch.cat([x[:, 0:half], x[:, half:self.horizon]], 0)
        refined = self.integrate(halves, torch.cat([start, after_mid], 0), torch.cat([before_mid, goal], 0), split_time,
                                 split_steps(steps, split_time), scene, opts, choices, guided)
        return torch.cat([refined[0:B], refined[B:2 * B]], 1)

    def sample(self, start: Tensor, goal: Tensor, noise: Tensor, renoise: Optional[Tensor],
               scene: Dict[str, Tensor], opts: Dict[str, float], choices: Dict[str, str]) -> Tensor:
        """start, goal (B, D) raw -> plans (B, T, D) raw, interior states clamped to
        the training range; under inpainting states 0 and T - 1 are start and goal."""
        x = self.sample_normalized(self.normalizer.normalize(start), self.normalizer.normalize(goal), noise, renoise,
                                   scene, opts, choices)
        return conditioned(self.normalizer.denormalize(x), start, goal, self.conditioning == "inpaint")
