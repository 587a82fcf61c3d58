"""Isolation check (issue 33, session 6; seconds, not in CI): does MuJoCo's soft friction, as the
ant's data use it (elliptic cone,
the ant's margin 0.01, default solref/solimp, RK4 1e-4), follow hard Coulomb on a sliding box?
A 1 kg box (capsule-free: a 0.1 m cube) on a plane with mu = 0.3, pushed by a constant horizontal
force F: Coulomb gives a = (F - mu m g)/m when F > mu m g and no motion below."""
import mujoco, numpy as np
XML = """<mujoco><option timestep="1e-4" integrator="RK4" cone="elliptic" gravity="0 0 -9.81"/>
<worldbody><geom type="plane" size="5 5 .1" friction="{mu} 0.5 0.5" margin="0.01"/>
<body name="box" pos="0 0 0.05"><freejoint/><geom type="box" size=".05 .05 .05" mass="1" friction="{mu} 0.5 0.5" margin="0.01"/></body>
</worldbody></mujoco>"""
# Run: .venv/bin/python tools/check/mujoco_friction_box.py
for mu in (0.3, 1.0):
    for F in (0.5 * mu * 9.81, 2.0 * mu * 9.81, 1.2 * mu * 9.81):
        m = mujoco.MjModel.from_xml_string(XML.format(mu=mu)); d = mujoco.MjData(m)
        for _ in range(5000):  # settle 0.5 s
            mujoco.mj_step(m, d)
        x0 = d.qpos[0]; v0 = d.qvel[0]
        T = 1.0
        for _ in range(int(T / m.opt.timestep)):
            d.xfrc_applied[1, 0] = F
            mujoco.mj_step(m, d)
        x1, v1 = d.qpos[0], d.qvel[0]
        a_meas = (v1 - v0) / T
        a_coul = max(0.0, (F - mu * 9.81) / 1.0)
        print(f"mu {mu} F/(mu m g) {F/(mu*9.81):.2f}: a MuJoCo {a_meas:.4f}, Coulomb {a_coul:.4f}, "
              f"effective mu {(F - a_meas)/9.81:.4f}; slide {x1-x0:.4f} m; z {d.qpos[2]:.5f}")
