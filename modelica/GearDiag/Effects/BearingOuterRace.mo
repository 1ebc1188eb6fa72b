within GearDiag.Effects;
model BearingOuterRace "Outer-race defect of the pinion bearing: force pulses at BPFO"
  // A smooth periodic pulse train exp(kappa*(cos(theta) - 1)), one pulse per ball pass.
  extends GearDiag.GearPair(F_extra = F_b*exp(kappa*(cos(2*pi*f_bpfo*time) - 1)));
  parameter Real F_b(unit="N", min=0) = 150 "Peak defect force";
  parameter Real kappa = 20 "Pulse sharpness";
  parameter Integer n_balls = 9 "Number of rolling elements (6205-type bearing)";
  parameter Real d_ball(unit="m") = 7.94e-3 "Ball diameter";
  parameter Real d_pitch(unit="m") = 39.04e-3 "Pitch diameter";
  parameter Real f_bpfo(unit="Hz") = n_balls/2*f_pinion*(1 - d_ball/d_pitch) "Ball pass frequency, outer race";
end BearingOuterRace;
