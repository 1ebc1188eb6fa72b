within GearDiag.Effects;
model BearingInnerRace "Inner-race defect of the pinion bearing: pulses at BPFI, modulated by the shaft turn"
  extends GearDiag.GearPair(F_extra = F_b*(1 + m_shaft*cos(2*pi*f_pinion*time))
                                      *exp(kappa*(cos(2*pi*f_bpfi*time) - 1)));
  parameter Real F_b(unit="N", min=0) = 150 "Peak defect force";
  parameter Real m_shaft(min=0, max=1) = 0.5 "Modulation depth by the load zone, once per turn";
  parameter Real kappa = 20 "Pulse sharpness";
  parameter Integer n_balls = 9 "Number of rolling elements (6205-type bearing)";
  parameter Real d_ball(unit="m") = 7.94e-3 "Ball diameter";
  parameter Real d_pitch(unit="m") = 39.04e-3 "Pitch diameter";
  parameter Real f_bpfi(unit="Hz") = n_balls/2*f_pinion*(1 + d_ball/d_pitch) "Ball pass frequency, inner race";
end BearingInnerRace;
