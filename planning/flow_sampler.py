# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# FlowSampler, the flow planner's sampler (SPEC section 2): Euler steps of the
# network's velocity from noise (t = 0) to a plan (t = 1), inpainting or
# direct conditioning, guidance after every step, and optional midpoint
# splitting. Submodules network (forward(x, t, cond)), normalizer and guide;
# attributes conditioning ("inpaint" or "direct"), splitting ("none" or
# "midpoint"), horizon (T). Settings: sampler.steps and the guide's.


def velocity(self, x: Tensor, t: Tensor, start: Tensor, goal: Tensor) -> Tensor:
    """The network's velocity (B, T', D) at normalized x (B, T', D), flow time
    t (B,), with the boundary conditions start, goal (B, D) normalized."""
    inpainting = self.conditioning == "inpaint"
    return self.network.forward(conditioned(x, start, goal, inpainting), t, condition_vector(start, goal, inpainting))


def integrate(self, x: Tensor, start: Tensor, goal: Tensor, t0: float, steps: int,
              scene: Dict[str, Tensor], opts: Dict[str, float], schedule: str, guided: bool) -> Tensor:
    """Euler from flow time t0 to 1 in `steps` steps:
    x <- x + h v(x, t_i); guide (at t_{i+1}); inpaint."""
    inpainting = self.conditioning == "inpaint"
    x = conditioned(x, start, goal, inpainting)
    h = (1.0 - t0) / steps
    for i in range(steps):
        t = torch.full([x.size(0)], t0 + i * h, dtype=x.dtype, device=x.device)
        x = x + h * self.velocity(x, t, start, goal)
        if guided:
            x = self.guide.step(x, t0 + (i + 1) * h, scene, opts, schedule)
        x = conditioned(x, start, goal, inpainting)
    return x


def sample_normalized(self, start: Tensor, goal: Tensor, noise: Tensor, renoise: Optional[Tensor],
                      scene: Dict[str, Tensor], opts: Dict[str, float], schedule: str) -> Tensor:
    """start, goal (B, D) normalized; noise, renoise (B, T, D) standard normal
    -> plans (B, T, D) normalized, unclamped."""
    guided = self.guide.active(scene, opts)
    steps = setting_int(opts, "sampler.steps")
    assert steps >= 1, "sampler.steps: expected at least one step, got " + str(steps)
    x = self.integrate(noise, start, goal, 0.0, steps, scene, opts, schedule, guided)
    if self.splitting == "none":
        return x
    assert renoise is not None, "plan: renoise: this planner splits trajectories and needs re-noising noise"
    # Midpoint splitting: the states on either side of the middle become the
    # boundaries of the two halves, so the joined plan has no duplicate state.
    B = x.size(0)
    half = self.horizon // 2
    before_mid = x[:, half - 1]
    after_mid = x[:, half]
    x = 0.5 * renoise + 0.5 * x
    halves = torch.cat([x[:, 0:half], x[:, half:self.horizon]], 0)
    refined = self.integrate(halves, torch.cat([start, after_mid], 0), torch.cat([before_mid, goal], 0), 0.5,
                             max(1, steps // 2), scene, opts, schedule, guided)
    return torch.cat([refined[0:B], refined[B:2 * B]], 1)


def sample(self, start: Tensor, goal: Tensor, noise: Tensor, renoise: Optional[Tensor],
           scene: Dict[str, Tensor], opts: Dict[str, float], schedule: str) -> Tensor:
    """start, goal (B, D) raw -> plans (B, T, D) raw, interior states clamped to
    the training range; under inpainting states 0 and T - 1 are start and goal."""
    x = self.sample_normalized(self.normalizer.normalize(start), self.normalizer.normalize(goal), noise, renoise,
                               scene, opts, schedule)
    return conditioned(self.normalizer.denormalize(x), start, goal, self.conditioning == "inpaint")
