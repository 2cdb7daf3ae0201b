# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# LatentSampler, the VAE baseline's planner ("Reaching Through Latent Space",
# SPEC section 2): activation maximization in the latent space of a state VAE.
# From the latent of the start state (its encoding's mean plus its standard
# deviation times `noise`), Adam steps on the latent lower
#   goal_weight |TCP(decode(z)) - TCP(goal)| + scale * guidance cost of the
#   decoded state + prior_weight |z|^2 / 2,
# and after `iterations` steps the decoded state becomes the next waypoint;
# once a waypoint's TCP is within goal_tolerance of the goal it is held. The
# goal is not imposed. Gradients are written out (the decoder's and the TCP's
# vector-Jacobian products). Submodules vae (encode, decode, decode_vjp),
# normalizer, robot and guide; attributes horizon, adam_beta1, adam_beta2,
# adam_epsilon. Settings: sampler.latent.* and the guide's.

from typing import Dict, Optional

import torch
from torch import Tensor

from flowplan.script.planning.sampling import setting_int


class LatentSampler:
    def sample(self, start: Tensor, goal: Tensor, noise: Tensor, renoise: Optional[Tensor],
               scene: Dict[str, Tensor], opts: Dict[str, float], choices: Dict[str, str]) -> Tensor:
        """start, goal (B, D) raw; noise (B, L) -> plans (B, T, D) raw."""
        B = start.size(0)
        D = start.size(1)
        J = self.robot.num_joints
        iterations = setting_int(opts, "sampler.latent.iterations")
        lr = opts["sampler.latent.lr"]
        goal_weight = opts["sampler.latent.goal_weight"]
        prior_weight = opts["sampler.latent.prior_weight"]
        tolerance = opts["sampler.latent.goal_tolerance"]
        scale = opts["guidance.scale"]
        guided = self.guide.active(scene, opts)
        beta1 = self.adam_beta1
        beta2 = self.adam_beta2
        goal_tcp = self.robot.tcp(goal[:, 0:J])
        scale_n = self.normalizer.raw_per_normalized().to(start.dtype)
        mean, log_var = self.vae.encode(self.normalizer.normalize(start))
        z = mean + torch.exp(0.5 * log_var) * noise
        m = torch.zeros_like(z)
        v = torch.zeros_like(z)
        done = torch.zeros([B, 1], dtype=z.dtype, device=z.device)
        waypoints = [start]
        adam_step = 0
        for i in range(self.horizon - 1):
            for it in range(iterations):
                x = self.normalizer.denormalize_unclamped(self.vae.decode(z))
                q = x[:, 0:J]
                diff = self.robot.tcp(q) - goal_tcp
                direction = diff / torch.norm(diff, 2, 1, True).clamp_min(1e-9)
                gradient = torch.cat([goal_weight * self.robot.tcp_vjp(q, direction),
                                      torch.zeros([B, D - J], dtype=z.dtype, device=z.device)], 1)
                if guided:
                    gradient = gradient + scale * self.guide.raw_gradient(x.view(B, 1, D), scene, opts).view(B, D)
                grad = self.vae.decode_vjp(z, gradient * scale_n) + prior_weight * z
                adam_step += 1
                m = beta1 * m + (1.0 - beta1) * grad
                v = beta2 * v + (1.0 - beta2) * grad * grad
                m_correction = 1.0 - beta1 ** float(adam_step)
                v_correction = 1.0 - beta2 ** float(adam_step)
                update = (m / m_correction) / (torch.sqrt(v / v_correction) + self.adam_epsilon)
                z = z - (lr * update) * (1.0 - done)
            waypoint = self.normalizer.denormalize(self.vae.decode(z))
            following = done * waypoints[-1] + (1.0 - done) * waypoint
            waypoints.append(following)
            reached = torch.norm(self.robot.tcp(following[:, 0:J]) - goal_tcp, 2, 1, True) < tolerance
            done = torch.max(done, reached.to(z.dtype))
        return torch.stack(waypoints, 1)
