within GearDiag.Examples;
model PairOnShafts "GearPair built from the drive train's components: a steady pinion, the mesh, the gear's inertia, a load"
  // With the pinion at its steady speed, the teeth's deflection obeys
  //   x'' = -r_g*w_g' = -(r_g^2/J_g)*F + r_g*T_load/J_g
  // which is GearPair's m*x'' = T/r_p - F for J_g = m*r_g^2 and T_load = T*r_g/r_p: the
  // mesh's acc, (T/r_p - F)/m, is GearPair's.
  parameter Real m(unit="kg") = 0.5 "GearPair's equivalent mass";
  GearDiag.Components.SteadySpeed drive "The pinion's shaft at its steady speed";
  GearDiag.Components.GearMesh mesh(m_s = m) "The pair's mesh";
  GearDiag.Components.Inertia gear(J = m*mesh.r_g^2) "The gear";
  GearDiag.Components.LoadTorque load(T = mesh.T*mesh.r_g/mesh.r_p) "The gear shaft's load";
  output Real acc(unit="m/s2") "Acceleration of the teeth's deflection: GearPair's acc";
  output Real disp(unit="m") "Deflection of the teeth";
equation
  connect(drive.flange, mesh.flange_a);
  connect(mesh.flange_b, gear.flange_a);
  connect(gear.flange_b, load.flange);
  acc = mesh.acc;
  disp = mesh.disp;
  annotation(Documentation(info="<html>
<p>GearPair built from the drive train's components: a steady pinion, the mesh, the gear's inertia, a load.</p>
<pre>
With the pinion at its steady speed, the teeth's deflection obeys
  x'' = -r_g*w_g' = -(r_g^2/J_g)*F + r_g*T_load/J_g
which is GearPair's m*x'' = T/r_p - F for J_g = m*r_g^2 and T_load = T*r_g/r_p: the
mesh's acc, (T/r_p - F)/m, is GearPair's.
</pre>
</html>"));
end PairOnShafts;
