within GearDiag.Effects;
model BearingBall "Rolling-element defect of a bearing of the pair (the pinion's, unless r_shaft says otherwise): strikes twice a turn of the ball ring a structural mode, stronger as the cage carries it through the load zone"
  // A spalled ball strikes the inner and the outer race once each in a turn about its own
  // axis (twice the ball spin frequency); the cage carries it round the bearing, through
  // the load zone once a cage turn (the fundamental train frequency), so its strikes are
  // strongest there (depth m_cage, the ball in the zone at cage phase phi_cage).
  extends GearDiag.GearPair(acc_sensor = der(v)
    + A_b*(1 - m_cage/2*(1 - cos(2*pi*f_ftf*t_angle - phi_cage)))
      *GearDiag.Functions.ringDown(t_angle, 2*f_bsf, f_mode, zeta_mode));
  parameter Real A_b(unit="m/s2", min=0) = 60 "Peak acceleration of one strike's ring-down in the load zone";
  parameter Real m_cage(unit="1", min=0, max=1) = 1 "Modulation depth by the load zone, once a cage turn (1: no strike opposite it)";
  parameter Real phi_cage(unit="rad") = 0 "Cage angle at which the faulty ball is in the load zone";
  parameter Real f_mode(unit="Hz") = 3000 "Natural frequency of the structural mode the strikes ring";
  parameter Real zeta_mode(unit="1", min=1e-3, max=0.5) = 0.05 "Damping ratio of that mode";
  parameter Real r_shaft(unit="1", min=0) = 1 "Speed of the bearing's shaft over the pinion's (1: the pinion's shaft)";
  parameter Integer n_balls(min=1) = 9 "Number of rolling elements (6205-type bearing; pydiag sets the machine's)";
  parameter Real d_ball(unit="m", min=0) = 7.94e-3 "Ball diameter";
  parameter Real d_pitch(unit="m", min=0) = 39.04e-3 "Pitch diameter";
  parameter Real alpha_contact(unit="rad") = 0 "Contact angle";
  parameter Real f_bsf(unit="Hz") = d_pitch/(2*d_ball)*f_pinion*r_shaft*(1 - (d_ball/d_pitch*cos(alpha_contact))^2) "Ball spin frequency";
  parameter Real f_ftf(unit="Hz") = f_pinion*r_shaft/2*(1 - d_ball/d_pitch*cos(alpha_contact)) "Fundamental train (cage) frequency";
  annotation(Documentation(info="<html>
<p>Rolling-element defect of a bearing of the pair (the pinion's, unless r_shaft says otherwise): strikes twice a turn of the ball ring a
structural mode, stronger as the cage carries it through the load zone.</p>
<pre>
A spalled ball strikes the inner and the outer race once each in a turn about its own
axis (twice the ball spin frequency); the cage carries it round the bearing, through
the load zone once a cage turn (the fundamental train frequency), so its strikes are
strongest there (depth m_cage, the ball in the zone at cage phase phi_cage).
</pre>
</html>"));
end BearingBall;
