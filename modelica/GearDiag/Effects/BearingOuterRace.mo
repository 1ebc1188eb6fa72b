within GearDiag.Effects;
model BearingOuterRace "Outer-race defect of a bearing of the pair (the pinion's, unless r_shaft says otherwise): strikes at BPFO ring a structural mode at the sensor"
  // Each rolling element passing the spall strikes the housing; the accelerometer sees a
  // structural mode ringing down after every strike (McFadden and Smith's model), added to
  // what it sees of the mesh. The mesh itself (disp) does not feel it.
  extends GearDiag.GearPair(acc_sensor = der(v)
    + A_b*GearDiag.Functions.ringDown(t_angle, f_bpfo, f_mode, zeta_mode));
  parameter Real A_b(unit="m/s2", min=0) = 60 "Peak acceleration of one strike's ring-down at the sensor";
  parameter Real f_mode(unit="Hz") = 3000 "Natural frequency of the structural mode the strikes ring";
  parameter Real zeta_mode(unit="1", min=1e-3, max=0.5) = 0.05 "Damping ratio of that mode";
  parameter Real r_shaft(unit="1", min=0) = 1 "Speed of the bearing's shaft over the pinion's (1: the pinion's shaft)";
  parameter Integer n_balls(min=1) = 9 "Number of rolling elements (6205-type bearing; pydiag sets the machine's)";
  parameter Real d_ball(unit="m", min=0) = 7.94e-3 "Ball diameter";
  parameter Real d_pitch(unit="m", min=0) = 39.04e-3 "Pitch diameter";
  parameter Real alpha_contact(unit="rad") = 0 "Contact angle";
  parameter Real f_bpfo(unit="Hz") = n_balls/2*f_pinion*r_shaft*(1 - d_ball/d_pitch*cos(alpha_contact)) "Ball pass frequency, outer race";
  annotation(Documentation(info="<html>
<p>Outer-race defect of a bearing of the pair (the pinion's, unless r_shaft says otherwise): strikes at BPFO ring a structural mode at the sensor.</p>
<pre>
Each rolling element passing the spall strikes the housing; the accelerometer sees a
structural mode ringing down after every strike (McFadden and Smith's model), added to
what it sees of the mesh. The mesh itself (disp) does not feel it.
</pre>
</html>"));
end BearingOuterRace;
