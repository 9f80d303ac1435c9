"""Builds a `pinocchio.Model` from kanegen's Pinocchio export (the text format of
`codegen/src/pinocchio.rs`, as `benches/pinocchio/cases.hpp` reads it), and maps kanegen's
state to Pinocchio's and Pinocchio's results back to kanegen's speeds."""

import numpy as np
import pinocchio as pin


class Exported:
    def __init__(self, text):
        tokens = text.split()
        pos = 0

        def take():
            nonlocal pos
            pos += 1
            return tokens[pos - 1]

        def expect(word):
            got = take()
            assert got == word, f"expected `{word}`, got `{got}`"

        def nums(n):
            return np.array([float(take()) for _ in range(n)])

        def se3():
            rot = nums(9).reshape(3, 3)
            return pin.SE3(rot, nums(3))

        expect("kanegen-pinocchio")
        assert take() == "1"
        expect("model")
        take()
        expect("nq")
        nq = int(take())
        expect("nv")
        nv = int(take())
        expect("dof")
        self.dof = int(take())
        model = pin.Model()
        expect("gravity")
        model.gravity.linear = nums(3)
        expect("joints")
        kinds = {
            "RX": pin.JointModelRX,
            "RY": pin.JointModelRY,
            "RZ": pin.JointModelRZ,
            "PX": pin.JointModelPX,
            "PY": pin.JointModelPY,
            "PZ": pin.JointModelPZ,
            "PLANAR": pin.JointModelPlanar,
        }
        for _ in range(int(take())):
            expect("joint")
            name = take()
            parent = int(take())
            kind = take()
            axis = nums(3)
            placement = se3()
            if kind == "RU":
                joint = pin.JointModelRevoluteUnaligned(axis)
            elif kind == "PU":
                joint = pin.JointModelPrismaticUnaligned(axis)
            else:
                joint = kinds[kind]()
            model.addJoint(parent, joint, placement, name)
        expect("bodies")
        for _ in range(int(take())):
            expect("body")
            take()
            joint = int(take())
            placement = se3()
            mass = float(take())
            com = nums(3)
            inertia = nums(9).reshape(3, 3)
            model.appendBodyToJoint(joint, pin.Inertia(mass, com, inertia), placement)
        assert (model.nq, model.nv) == (nq, nv)
        expect("armature")
        model.armature = nums(nv)
        expect("speeds")
        take()
        self.v_index, self.sign = [], []
        for _ in range(self.dof):
            expect("speed")
            take()
            self.v_index.append(int(take()))
            self.sign.append(float(take()))
        expect("coordinates")
        take()
        self.coords = []
        for _ in range(self.dof):
            expect("coordinate")
            take()
            kind = take()
            index = int(take())
            sign = float(take())
            self.coords.append((kind, index, sign))
        expect("end")
        self.model = model
        self.data = model.createData()
        # S: v = S u.
        self.S = np.zeros((nv, self.dof))
        for i, (v, s) in enumerate(zip(self.v_index, self.sign)):
            self.S[v, i] = s

    def configuration(self, q):
        out = np.zeros(self.model.nq)
        for x, (kind, index, sign) in zip(q, self.coords):
            if kind == "joint":
                out[index] = sign * x
            elif kind == "planar_x":
                out[index] = x
            else:
                out[index] = np.cos(x)
                out[index + 1] = np.sin(x)
        return out

    def velocity(self, u):
        return self.S @ u

    def mass_matrix(self, q):
        m = pin.crba(self.model, self.data, self.configuration(q))
        m = np.triu(m) + np.triu(m, 1).T
        return self.S.T @ m @ self.S

    def gravity(self, q):
        return self.S.T @ pin.computeGeneralizedGravity(self.model, self.data, self.configuration(q))

    def inverse_dynamics(self, q, u, ud):
        pq = self.configuration(q)
        return self.S.T @ pin.rnea(self.model, self.data, pq, self.velocity(u), self.velocity(ud))

    def nonlinear_effects(self, q, u):
        pq = self.configuration(q)
        return self.S.T @ pin.nonLinearEffects(self.model, self.data, pq, self.velocity(u))
