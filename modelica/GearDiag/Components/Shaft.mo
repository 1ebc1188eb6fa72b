within GearDiag.Components;
model Shaft "A shaft's torsional compliance between two bodies on it"
  // The twist phi of a shaft of torsional stiffness k_t and damping d_t under the torque
  // it carries, tau_0 at steady running (its start: the shaft starts twisted by its load):
  //   phi' = flange_b.w - flange_a.w,   tau = k_t*phi + d_t*phi'
  // The shaft's own inertia belongs to the Inertia components on its ends.
  parameter Real k_t(unit="N.m/rad", min=0) = 1e5 "Torsional stiffness";
  parameter Real d_t(unit="N.m.s/rad", min=0) = 5 "Torsional damping";
  parameter Real tau_0(unit="N.m") = 0 "Torque the shaft carries at steady running";
  GearDiag.Interfaces.Flange flange_a "Driving end";
  GearDiag.Interfaces.Flange flange_b "Driven end";
  Real phi(unit="rad", start=-tau_0/k_t, fixed=true, nominal=1e-4) "Twist: flange_b's angle over flange_a's";
  Real tau(unit="N.m") "Torque the shaft carries from flange_a to flange_b";
equation
  der(phi) = flange_b.w - flange_a.w;
  tau = -(k_t*phi + d_t*der(phi));
  flange_a.tau = tau;
  flange_b.tau = -tau;
  annotation(Documentation(info="<html>
<p>A shaft's torsional compliance between two bodies on it.</p>
<pre>
The twist phi of a shaft of torsional stiffness k_t and damping d_t under the torque
it carries, tau_0 at steady running (its start: the shaft starts twisted by its load):
  phi' = flange_b.w - flange_a.w,   tau = k_t*phi + d_t*phi'
The shaft's own inertia belongs to the Inertia components on its ends.
</pre>
</html>"));
end Shaft;
