# A guidance cost of one's own (docs/planning.md): keep the Franka's TCP at
# least 0.25 m above the table. flowplan compiles this method onto a module
# whose submodule `robot` has the robot's kinematics (kinematics/arm.py) and
# takes its gradient by autograd. q, qd: (B, T, J) raw joint positions and
# velocities; scene: the call's obstacles; returns one value per plan (B,).
def cost(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor:
    height = self.robot.tcp(q)[:, :, 2]                # (B, T) m
    return (torch.relu(0.25 - height) ** 2).sum(1)     # (B,)
