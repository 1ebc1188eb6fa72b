within GearDiag.Functions;
function ringDown "Acceleration of a structural mode struck once per period"
  input Real t(unit="s") "Time";
  input Real f_strike(unit="Hz") "Strikes per second";
  input Real f_n(unit="Hz") "Natural frequency of the mode";
  input Real zeta "Damping ratio of the mode";
  output Real a "Response to the last strike, peak about 1";
protected
  Real tau(unit="s") "Time since the last strike";
  Real alpha(unit="1/s") "Decay rate, zeta*w_n";
  Real beta(unit="rad/s") "Damped angular frequency";
algorithm
  // Each strike (a rolling element over a spall) rings the mode; the ring-down of the one
  // before has decayed by exp(-zeta*2*pi*f_n/f_strike) when the next comes (9 e-folds for
  // 3 kHz, 5 %, 90 Hz), so only the last is kept. Out of the mesh's equations of motion:
  // the solver never sees the jump at a strike. A strike moves the mode as exp(-alpha
  // tau)*sin(beta tau); the sensor sees its acceleration (over w_n^2), so lines below the
  // mode fall as (f/f_n)^2, as the accelerance of a mode does.
  tau := mod(t, 1/f_strike);
  alpha := zeta*2*GearDiag.pi*f_n;
  beta := 2*GearDiag.pi*f_n*sqrt(1 - zeta^2);
  a := exp(-alpha*tau)*((beta^2 - alpha^2)*sin(beta*tau) + 2*alpha*beta*cos(beta*tau))
       /(alpha^2 + beta^2);
  annotation(Documentation(info="<html>
<p>Acceleration of a structural mode struck once per period.</p>
</html>"));
end ringDown;
