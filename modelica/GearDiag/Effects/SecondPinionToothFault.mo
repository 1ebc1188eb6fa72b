within GearDiag.Effects;
model SecondPinionToothFault "A second faulty pinion tooth: the mesh is softer while it is in contact"
  // As GearToothFault, on the pinion: the mesh stiffness drops by d_f2 of K while pinion
  // tooth tooth2 carries the load alone, by d_f2/q_c in double contact, once a pinion turn
  // (the paper's faulty tooth 0 stays as it is).
  extends GearDiag.GearPair(k_mod = -d_f2*GearDiag.Functions.toothWindow(f_mesh*t_angle, Np, tooth2, eps_c, q_c, r_c));
  parameter Real d_f2(unit="1", min=0, max=1) = 0.2 "Relative loss of mesh stiffness while the second faulty tooth is alone in contact";
  parameter Real tooth2(unit="1", min=0) = 5 "Index of the second faulty pinion tooth (0 is the first)";
  annotation(Documentation(info="<html>
<p>A second faulty pinion tooth: the mesh is softer while it is in contact.</p>
<pre>
As GearToothFault, on the pinion: the mesh stiffness drops by d_f2 of K while pinion
tooth tooth2 carries the load alone, by d_f2/q_c in double contact, once a pinion turn
(the paper's faulty tooth 0 stays as it is).
</pre>
</html>"));
end SecondPinionToothFault;
