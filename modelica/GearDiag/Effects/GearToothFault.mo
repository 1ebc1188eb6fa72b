within GearDiag.Effects;
model GearToothFault "A faulty tooth on the driven gear: the mesh is softer while it is in contact"
  // As the pinion's d_f (GearPair): the mesh stiffness drops by d_g of K while the faulty
  // gear tooth carries the load alone, by d_g/q_c in double contact, once a gear turn
  // (GearDiag.Functions.toothWindow).
  extends GearDiag.GearPair(k_mod = -d_g*GearDiag.Functions.toothWindow(f_mesh*t_angle, Ng, tooth_g, eps_c, q_c, r_c));
  parameter Real d_g(unit="1", min=0, max=1) = 0.2 "Relative loss of mesh stiffness while the faulty gear tooth is alone in contact";
  parameter Real tooth_g(unit="1", min=0) = 0 "Index of the faulty gear tooth: the one meshing with pinion tooth 0 at the start is 0";
  annotation(Documentation(info="<html>
<p>A faulty tooth on the driven gear: the mesh is softer while it is in contact.</p>
<pre>
As the pinion's d_f (GearPair): the mesh stiffness drops by d_g of K while the faulty
gear tooth carries the load alone, by d_g/q_c in double contact, once a gear turn
(GearDiag.Functions.toothWindow).
</pre>
</html>"));
end GearToothFault;
