within GearDiag.Effects;
model BearingInnerRace "Inner-race defect of a bearing of the pair (the pinion's, unless r_shaft says otherwise): strikes at BPFI ring a structural mode, stronger in the load zone"
  // As BearingOuterRace, but the spall turns with the shaft: its strikes are strongest when
  // it passes the load zone, once a turn of its shaft (depth m_shaft, the zone at phase phi_zone).
  extends GearDiag.GearPair(acc_sensor = der(v)
    + A_b*(1 - m_shaft/2*(1 - cos(2*pi*f_pinion*r_shaft*t_angle - phi_zone)))
      *GearDiag.Functions.ringDown(t_angle, f_bpfi, f_mode, zeta_mode));
  parameter Real A_b(unit="m/s2", min=0) = 60 "Peak acceleration of one strike's ring-down in the load zone";
  parameter Real m_shaft(unit="1", min=0, max=1) = 1 "Modulation depth by the load zone, once per turn (1: no strike opposite it)";
  parameter Real phi_zone(unit="rad") = 0 "Angle of the bearing's shaft at which the spall is in the load zone";
  parameter Real f_mode(unit="Hz") = 3000 "Natural frequency of the structural mode the strikes ring";
  parameter Real zeta_mode(unit="1", min=1e-3, max=0.5) = 0.05 "Damping ratio of that mode";
  parameter Real r_shaft(unit="1", min=0) = 1 "Speed of the bearing's shaft over the pinion's (1: the pinion's shaft)";
  parameter Integer n_balls(min=1) = 9 "Number of rolling elements (6205-type bearing; pydiag sets the machine's)";
  parameter Real d_ball(unit="m", min=0) = 7.94e-3 "Ball diameter";
  parameter Real d_pitch(unit="m", min=0) = 39.04e-3 "Pitch diameter";
  parameter Real alpha_contact(unit="rad") = 0 "Contact angle";
  parameter Real f_bpfi(unit="Hz") = n_balls/2*f_pinion*r_shaft*(1 + d_ball/d_pitch*cos(alpha_contact)) "Ball pass frequency, inner race";
  annotation(Documentation(info="<html>
<p>Inner-race defect of a bearing of the pair (the pinion's, unless r_shaft says otherwise): strikes at BPFI ring a structural mode, stronger in the load zone.</p>
<pre>
As BearingOuterRace, but the spall turns with the shaft: its strikes are strongest when
it passes the load zone, once a turn of its shaft (depth m_shaft, the zone at phase phi_zone).
</pre>
</html>"));
end BearingInnerRace;
