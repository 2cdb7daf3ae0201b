# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# DdpmSampler, Motion Planning Diffusion's sampler: diffusion_steps ancestral DDPM steps of
# an epsilon-predicting network, guidance on the posterior mean (several
# gradient steps) in the last ceil(guide_fraction · diffusion_steps) steps, then extra
# noise-free guided steps. Submodules network, normalizer and guide; buffers
# x0_from_x, x0_from_eps, mean_x0, mean_x, noise_std (diffusion_steps,)
# float64 (the schedule's coefficients); attributes conditioning, diffusion_steps,
# guide_on ("posterior_mean": MPD's guidance of the posterior mean before the
# step's noise; "sample_by_variance": the Flow Planner paper's baseline, steps
# on the noised sample weighted by the step's posterior variance).
# Settings: sampler.ddpm.* and the guide's.

from typing import Dict, Optional

import torch
from torch import Tensor

from flowplan.script.models.conditioning import condition_vector
from flowplan.script.planning.sampling import ceil_int, conditioned, setting_int


class DdpmSampler:
    def denoise(self, x: Tensor, k: int, start: Tensor, goal: Tensor, guided: bool,
                scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tensor:
        """The posterior mean (B, T, D) of step k from x (B, T, D) normalized, guided."""
        inpainting = self.conditioning == "inpaint"
        t = torch.full([x.size(0)], float(k), dtype=x.dtype, device=x.device)
        eps = self.network.forward(x, t, condition_vector(start, goal, inpainting))
        x0 = torch.clamp(float(self.x0_from_x[k]) * x - float(self.x0_from_eps[k]) * eps, -1.0, 1.0)
        mean = float(self.mean_x0[k]) * x0 + float(self.mean_x[k]) * x
        if guided and self.guide_on == "posterior_mean":
            for i in range(setting_int(opts, "sampler.ddpm.guide_iterations")):
                mean = conditioned(mean - opts["guidance.scale"] * self.guide.gradient(mean, scene, opts), start, goal, inpainting)
        return mean

    def sample(self, start: Tensor, goal: Tensor, noise: Tensor, renoise: Optional[Tensor],
               scene: Dict[str, Tensor], opts: Dict[str, float], choices: Dict[str, str]) -> Tensor:
        """start, goal (B, D) raw; noise (B, T, D); renoise (B, diffusion_steps - 1, T, D), the
        noise of the ancestral steps -> plans (B, T, D) raw."""
        assert renoise is not None, "plan: renoise: expected the noise of the DDPM steps"
        inpainting = self.conditioning == "inpaint"
        s = self.normalizer.normalize(start)
        g = self.normalizer.normalize(goal)
        guided = self.guide.active(scene, opts)
        steps = self.diffusion_steps
        guided_steps = ceil_int(opts["sampler.ddpm.guide_fraction"] * steps - 1e-9)
        noise_scale = opts["sampler.ddpm.noise_scale"]
        x = conditioned(noise, s, g, inpainting)
        for j in range(steps):
            k = steps - 1 - j
            x = self.denoise(x, k, s, g, guided and k < guided_steps, scene, opts)
            if k > 0:
                x = x + (noise_scale * float(self.noise_std[k])) * renoise[:, j]
            x = conditioned(x, s, g, inpainting)
            if guided and k < guided_steps and self.guide_on == "sample_by_variance":
                weight = opts["guidance.scale"] * float(self.noise_std[k]) ** 2
                for i in range(setting_int(opts, "sampler.ddpm.guide_iterations")):
                    x = conditioned(x - weight * self.guide.gradient(x, scene, opts), s, g, inpainting)
        for e in range(setting_int(opts, "sampler.ddpm.extra_steps")):
            x = conditioned(self.denoise(x, 0, s, g, guided, scene, opts), s, g, inpainting)
        return conditioned(self.normalizer.denormalize(x), start, goal, inpainting)
