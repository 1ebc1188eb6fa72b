within GearDiag.Functions;
function ringDown "Acceleration of a structural mode struck once per period: a decaying sine"
  input Real t(unit="s") "Time";
  input Real f_strike(unit="Hz") "Strikes per second";
  input Real f_n(unit="Hz") "Natural frequency of the mode";
  input Real zeta "Damping ratio of the mode";
  output Real a "Response to the last strike, peak about 1";
protected
  Real tau(unit="s") "Time since the last strike";
algorithm
  // Each strike (a rolling element over a spall) rings the mode; the ring-down of the one
  // before has decayed by exp(-zeta*2*pi*f_n/f_strike) when the next comes (9 e-folds for
  // 3 kHz, 5 %, 90 Hz), so only the last is kept. Out of the mesh's equations of motion:
  // the solver never sees the jump at a strike.
  tau := mod(t, 1/f_strike);
  a := exp(-zeta*2*GearDiag.pi*f_n*tau)*sin(2*GearDiag.pi*f_n*tau);
end ringDown;
