within GearDiag.Components;
model GearMesh "A gear stage's mesh between its pinion's and its gear's shafts, along the line of action"
  // The teeth deflect along the line of action by x = r_p*theta_p - r_g*theta_g (theta:
  // each shaft's angle over its steady rotation, each in its own sense of turning) and push
  //   F = k(t)*(x - e(t)) + c*x'
  // against the pinion's turning (torque r_p*F) and with the gear's (r_g*F); k(t) and e(t)
  // are the paper's (Interfaces.PartialMeshLaw), at the stage's own teeth and pinion speed.
  // The mesh has no inertia: the wheels' are Inertia components on its flanges. An
  // accelerometer on the housing sees the change of the mesh force through the housing
  // far above its modes, (T/r_p + F_extra - F)/m_s (acc). A pinion at its steady speed and a gear of
  // inertia m_s*r_g^2 under a load T*r_g/r_p make GearPair of mass m_s: the same acc
  // (tests/fmu_build hold them to it). k_mod, e_extra, F_extra, t_angle (the law's),
  // contact and acc_sensor are hooks with neutral declaration equations, as GearPair's:
  // F_extra is a force on the line of action from outside the mesh (a torque ripple of
  // the stage's drive or load over the pinion's radius), taken by the gear's shaft, so
  // that the mesh's balance is GearPair's with it; its t_angle starts t_phase ahead (a
  // machine's stage meshing at a phase of its own relative to its first stage's), so
  // that an effect's angle adds to the stage's phase.
  extends GearDiag.Interfaces.PartialMeshLaw(t_angle = time + t_phase);
  parameter Real t_phase(unit="s") = 0 "Time the mesh's angle is ahead of its steady turning by (a machine's stage relative to its first)";
  parameter Real r_g(unit="m") = r_p*Ng/Np "Gear pitch radius";
  parameter Real m_s(unit="kg") = 0.5 "Apparent mass of the housing at the sensor: what the mesh force's change accelerates";
  GearDiag.Interfaces.Flange flange_a "The pinion's shaft";
  GearDiag.Interfaces.Flange flange_b "The gear's shaft";
  Real x(unit="m", start=x_static, fixed=true, nominal=1e-5) "Deflection of the teeth along the line of action";
  Real F_extra(unit="N") = 0 "Extra force on the line of action from outside the mesh, taken by the gear's shaft (effects)";
  Real contact = 1 "Contact factor, 1 while the teeth touch (effects)";
  Real acc_sensor(unit="m/s2") = (T/r_p + F_extra - mesh_force)/m_s "What the acc sensor sees of this mesh (effects: a transfer path)";
  output Real acc(unit="m/s2") "Acceleration at the sensor";
  output Real mesh_force(unit="N") "Force between the teeth";
  output Real disp(unit="m") "Deflection of the teeth";
equation
  der(x) = r_p*flange_a.w - r_g*flange_b.w;
  mesh_force = contact*stiffness*(x - e_ate - e_dte - e_extra) + c*der(x);
  flange_a.tau = r_p*mesh_force;
  flange_b.tau = -r_g*(mesh_force - F_extra);
  acc = acc_sensor;
  disp = x;
  annotation(Documentation(info="<html>
<p>A gear stage's mesh between its pinion's and its gear's shafts, along the line of action.</p>
<pre>
The teeth deflect along the line of action by x = r_p*theta_p - r_g*theta_g (theta:
each shaft's angle over its steady rotation, each in its own sense of turning) and push
  F = k(t)*(x - e(t)) + c*x'
against the pinion's turning (torque r_p*F) and with the gear's (r_g*F); k(t) and e(t)
are the paper's (Interfaces.PartialMeshLaw), at the stage's own teeth and pinion speed.
The mesh has no inertia: the wheels' are Inertia components on its flanges. An
accelerometer on the housing sees the change of the mesh force through the housing
far above its modes, (T/r_p + F_extra - F)/m_s (acc). A pinion at its steady speed and a gear of
inertia m_s*r_g^2 under a load T*r_g/r_p make GearPair of mass m_s: the same acc
(tests/fmu_build hold them to it). k_mod, e_extra, F_extra, t_angle (the law's),
contact and acc_sensor are hooks with neutral declaration equations, as GearPair's:
F_extra is a force on the line of action from outside the mesh (a torque ripple of
the stage's drive or load over the pinion's radius), taken by the gear's shaft, so
that the mesh's balance is GearPair's with it; its t_angle starts t_phase ahead (a
machine's stage meshing at a phase of its own relative to its first stage's), so
that an effect's angle adds to the stage's phase.
</pre>
</html>"));
end GearMesh;
