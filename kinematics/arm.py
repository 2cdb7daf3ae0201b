# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# Arm, batched kinematics of a tree of hinge and prismatic joints, built by
# kinematics/robot.cc from a RobotDescription. Shapes: M configurations,
# J joints, S collision spheres, W = 3 (a link count is written "links"). The dtype and device of the
# results follow q; the tables are float64 buffers.
#
# Buffers: fixed (links, 4, 4) link poses in their parents at q = 0; fixed_cross,
# fixed_cross_sq (links, 4, 4) those poses times [a]x and [a]x^2 of each link's
# hinge axis; link_joint
# (links,) int64 the joint turning each link (0 for a welded one) and link_turns
# (links,) 1 for a turned link, 0 for a welded one; tcp_pose
# (4, 4) the TCP in its link;
# frame_points (links * 4, S + 2J) points fixed in the links, homogeneous, in
# rows 4 l .. 4 l + 3 of their link l and zero elsewhere: the spheres' centres
# (S), the unit hinge axes (J, directions, w = 0) and a point on each hinge (J);
# sphere_radii (S,); ancestors
# (J, S) 1 where joint j moves sphere s; tcp_ancestors (J,); home, lower,
# upper (J,); link_slides (links,) 1 for a slid link, fixed_slide (links, 4, 4)
# its pose times [0 a; 0 0], joint_slides, joint_turns (J,) 1 for a prismatic
# (revolute) joint, used when the attribute has_slides is set ("hinge" below
# then also means a slide's axis). Attributes: parents, joints (List[int], per link), tcp_link,
# num_links, num_joints, workspace_dim, num_spheres, ik_* solver settings.

from typing import List, Optional, Tuple

import torch
from torch import Tensor

from flowplan.script.kinematics.kinematics import rotation_vector


class Arm:
    def link_frames(self, q: Tensor) -> List[Tensor]:
        """Link poses in the world, one tensor (M, 4, 4) per link, for q (M, J)."""
        M = q.size(0)
        angles = (q.index_select(1, self.link_joint.to(q.device)) * self.link_turns.to(q.dtype)).view(M, -1, 1, 1)
        # Every link's pose in its parent at once, F R with Rodrigues' R = I + sin [a]x + (1 - cos) [a]x^2 (a
        # welded link turns by 0) multiplied out, F + sin F[a]x + (1 - cos) F[a]x^2: element-wise products of
        # (M, links, 4, 4) instead of a broadcast matrix product (3x faster at 64 states); then the tree from the
        # root outwards.
        local = self.fixed.to(q.dtype) + torch.sin(angles) * self.fixed_cross.to(q.dtype) + \
            (1.0 - torch.cos(angles)) * self.fixed_cross_sq.to(q.dtype)  # (M, links, 4, 4)
        if self.has_slides:
            # A prismatic link slides along its axis: F Trans(v a) = F + v F [0 a; 0 0] (link_turns is 0 for it).
            slides = (q.index_select(1, self.link_joint.to(q.device)) * self.link_slides.to(q.dtype)).view(M, -1, 1, 1)
            local = local + slides * self.fixed_slide.to(q.dtype)
        frames: List[Tensor] = []
        for link in range(self.num_links):
            parent = self.parents[link]
            # bmm, not matmul: the (M, 4, 4) products need no broadcasting, and matmul's dispatch cost 20 % here.
            frames.append(local[:, link] if parent < 0 else torch.bmm(frames[parent], local[:, link]))
        return frames

    def tcp_frame(self, frames: List[Tensor]) -> Tensor:
        """The TCP pose (M, 4, 4) from the link frames."""
        carrier = frames[self.tcp_link]
        return torch.matmul(carrier, self.tcp_pose.to(carrier.dtype))

    def fixed_points(self, stacked: Tensor, first: int, count: int) -> Tensor:
        """Columns first .. first + count - 1 of frame_points in the world (M, count, 3), from the link frames
        stacked (M, links, 4, 4): the top three rows of every link pose side by side (M * 3, links * 4) times
        the points, one matrix product however many."""
        M = stacked.size(0)
        rows = stacked[:, :, 0:3, :].transpose(1, 2).reshape(M * 3, 4 * stacked.size(1))
        points = self.frame_points.narrow(1, first, count).to(stacked.dtype)
        return torch.mm(rows, points).view(M, 3, count).transpose(1, 2)

    def hinges(self, stacked: Tensor) -> Tuple[Tensor, Tensor]:
        """Unit hinge axes (M, J, 3) and points on them (M, J, 3) in the world, from
        the link frames stacked (M, links, 4, 4)."""
        J = self.num_joints
        both = self.fixed_points(stacked, self.num_spheres, 2 * J)
        return both[:, 0:J], both[:, J:2 * J]

    def tcp(self, q: Tensor) -> Tensor:
        """TCP positions (..., 3), m, of joint angles q (..., J), rad."""
        assert q.dim() >= 1 and q.size(-1) == self.num_joints, "tcp: q: expected (..., " + str(self.num_joints) + "), got " + str(q.shape)
        shape = list(q.shape[:-1])
        flat = q.reshape(-1, self.num_joints)
        return self.tcp_frame(self.link_frames(flat))[:, 0:3, 3].reshape(shape + [3])

    def spheres(self, q: Tensor) -> Tuple[Tensor, Tensor, Tensor]:
        """Collision sphere centres (M, S, 3) of q (M, J), with the hinge axes and
        points (M, J, 3) that spheres_vjp needs."""
        stacked = torch.stack(self.link_frames(q), 1)  # (M, links, 4, 4)
        S = self.num_spheres
        J = self.num_joints
        points = self.fixed_points(stacked, 0, S + 2 * J)  # the centres and hinges in one product
        return points[:, 0:S].contiguous(), points[:, S:S + J], points[:, S + J:S + 2 * J]

    def spheres_vjp(self, centres: Tensor, axes: Tensor, origins: Tensor, rows: Tensor, g: Tensor) -> Tensor:
        """d/dq of sum_i <g_i, c_{rows_i}(q)> -> (M, J): centres (M, S, 3) and the
        hinges of spheres(q), rows (n,) int64 indices into the M S centres (m S + s;
        the centres with a gradient, usually a few), g (n, 3). Written out: with
        dc_s/dq_j = A[j, s] a_j x (c_s - p_j), configuration m's product is
        a_j . (sum_i A[j, s_i] c_i x g_i - p_j x sum_i A[j, s_i] g_i) over its rows."""
        M = centres.size(0)
        S = centres.size(1)
        J = self.num_joints
        c = centres.reshape(M * S, 3).index_select(0, rows)                        # (n, 3)
        both = torch.cat([torch.cross(c, g, -1), g], 1)                             # (n, 6)
        weights = self.ancestors.to(g.dtype).t().index_select(0, torch.remainder(rows, S))  # (n, J): A[j, s_i]
        summed = torch.zeros([M, J, 6], dtype=g.dtype, device=g.device).index_add_(
            0, torch.div(rows, S, rounding_mode="floor"), weights.unsqueeze(2) * both.unsqueeze(1))  # (M, J, 6)
        turned = (axes * (summed[:, :, 0:3] - torch.cross(origins, summed[:, :, 3:6], -1))).sum(-1)
        if not self.has_slides:
            return turned
        # A prismatic joint j moves every point below it along a_j: dc_s/dq_j = A[j, s] a_j.
        slid = (axes * summed[:, :, 3:6]).sum(-1)
        return turned * self.joint_turns.to(g.dtype) + slid * self.joint_slides.to(g.dtype)

    def tcp_vjp(self, q: Tensor, g: Tensor) -> Tensor:
        """d/dq of sum <g, tcp(q)>: q (M, J), g (M, 3) -> (M, J), written out
        (dp/dq_j = a_j x (p - o_j) for the joints that move the TCP)."""
        frames = self.link_frames(q)
        position = self.tcp_frame(frames)[:, 0:3, 3]
        axes, origins = self.hinges(torch.stack(frames, 1))
        arm = position.unsqueeze(1) - origins
        product = (axes * torch.cross(arm, g.unsqueeze(1).expand_as(arm), -1)).sum(-1)
        if self.has_slides:  # dp/dq_j = a_j for a prismatic joint
            product = product * self.joint_turns.to(q.dtype) + (axes * g.unsqueeze(1)).sum(-1) * self.joint_slides.to(q.dtype)
        return product * self.tcp_ancestors.to(q.dtype).unsqueeze(0)

    def sphere_centres(self, q: Tensor) -> Tensor:
        """Collision sphere centres (..., S, 3) of q (..., J)."""
        assert q.dim() >= 1 and q.size(-1) == self.num_joints, "sphere_centres: q: expected (..., " + str(self.num_joints) + "), got " + str(q.shape)
        shape = list(q.shape[:-1])
        centres, axes, origins = self.spheres(q.reshape(-1, self.num_joints))
        return centres.reshape(shape + [self.num_spheres, 3])

    def collision_spheres(self, q: Tensor) -> Tensor:
        """Centre and radius (..., S, 4) of every collision sphere of q (..., J)."""
        centres = self.sphere_centres(q)
        radii = self.sphere_radii.to(centres.dtype).expand(centres.shape[:-1]).unsqueeze(-1)
        return torch.cat([centres, radii], -1)

    def ik_solve(self, targets: Tensor, seed: Tensor) -> Tuple[Tensor, Tensor, Tensor, Tensor]:
        """Joint angles that put the TCP at targets (M, 3), m, with the TCP's
        orientation at the home posture (the Franka's: the gripper pointing down),
        from seed (M, J): damped least squares (steps of at most ik_max_step rad,
        joints ik_limit_margin inside their limits) with a pull towards home in the
        task's null space; converged configurations stop moving. float64.
        Returns q (M, J), position error (M,) m, orientation error (M,) rad and
        converged (M,) bool."""
        target = targets.double()
        M = target.size(0)
        J = self.num_joints
        home = self.home.view(1, J)
        lower = self.lower.view(1, J) + self.ik_limit_margin
        upper = self.upper.view(1, J) - self.ik_limit_margin
        goal_rotation = self.tcp_frame(self.link_frames(home))[:, 0:3, 0:3]
        moves_tcp = self.tcp_ancestors.view(1, J, 1)
        identity = torch.eye(J, dtype=target.dtype).unsqueeze(0)
        damping = self.ik_damping * self.ik_damping * torch.eye(6, dtype=target.dtype).unsqueeze(0)
        q = torch.max(torch.min(seed.double(), upper), lower)
        position_error = torch.zeros([M], dtype=target.dtype)
        orientation_error = torch.zeros([M], dtype=target.dtype)
        converged = position_error > 0.0
        for iteration in range(self.ik_iterations + 1):
            frames = self.link_frames(q)
            tcp = self.tcp_frame(frames)
            position = tcp[:, 0:3, 3]
            error = torch.cat([target - position, rotation_vector(torch.matmul(goal_rotation, tcp[:, 0:3, 0:3].transpose(1, 2)))], 1)
            position_error = torch.norm(error[:, 0:3], 2, 1)
            orientation_error = torch.norm(error[:, 3:6], 2, 1)
            converged = (position_error < self.ik_position_tolerance) & (orientation_error < self.ik_orientation_tolerance)
            if iteration == self.ik_iterations or bool(converged.all()):
                break
            # Geometric Jacobian (M, 6, J): a_j x (p - o_j) and a_j for the joints that move the TCP.
            axes, origins = self.hinges(torch.stack(frames, 1))
            axes = axes * moves_tcp
            linear = torch.cross(axes, position.unsqueeze(1) - origins, -1)
            angular = axes
            if self.has_slides:  # a prismatic joint's column: (a_j, 0)
                slides = self.joint_slides.view(1, J, 1)
                linear = linear * (1.0 - slides) + axes * slides
                angular = axes * (1.0 - slides)
            jacobian = torch.cat([linear, angular], 2).transpose(1, 2)
            jt = jacobian.transpose(1, 2)
            step = torch.matmul(jt, torch.linalg_solve(torch.matmul(jacobian, jt) + damping, error.unsqueeze(-1))).squeeze(-1)
            null_space = identity - torch.matmul(torch.linalg_pinv(jacobian), jacobian)
            step = step + self.ik_posture_gain * torch.matmul(null_space, (home - q).unsqueeze(-1)).squeeze(-1)
            biggest = step.abs().amax(1, True)
            step = step * (self.ik_max_step / biggest.clamp_min(self.ik_max_step))
            step = step * torch.logical_not(converged).double().unsqueeze(1)
            q = torch.max(torch.min(q + step, upper), lower)
        return q, position_error, orientation_error, converged

    def ik(self, tcp: Tensor, seed: Optional[Tensor] = None) -> Tensor:
        """Joint angles (..., J) that put the TCP at tcp (..., 3), m, with its
        orientation at the home posture, solved from seed (..., J) if given and, for
        targets that fails for, from home. Raises if a target is out of reach."""
        assert tcp.dim() >= 1 and tcp.size(-1) == 3, "ik: tcp: expected (..., 3), TCP positions in m, got " + str(tcp.shape)
        shape = list(tcp.shape[:-1])
        target = tcp.reshape(-1, 3)
        home = self.home.view(1, self.num_joints).expand(target.size(0), self.num_joints)
        q, position_error, orientation_error, converged = self.ik_solve(target, home if seed is None else seed.reshape(-1, self.num_joints))
        if seed is not None and not bool(converged.all()):
            again, position_error2, orientation_error2, converged2 = self.ik_solve(target, home)
            retry = torch.logical_not(converged).unsqueeze(1)
            q = torch.where(retry, again, q)
            converged = torch.where(retry.squeeze(1), converged2, converged)
        assert bool(converged.all()), "ik: a target is out of reach with the TCP orientation of the home posture"
        return q.reshape(shape + [self.num_joints]).to(tcp.dtype)
