within GearDiag.Functions;
function formWave "Unit-amplitude periodic wave between a cosine (f_f = 0) and a square wave (f_f -> 1)"
  input Real theta(unit="rad") "Phase angle";
  input Real f_f "Form factor, 0 <= f_f < 1";
  output Real s "Wave value in [-1, 1]";
protected
  Real c "cos(theta)";
algorithm
  // s = cos(theta) / sqrt((1 - f_f) + f_f*cos(theta)^2)
  // f_f = 0: s = cos(theta).  f_f -> 1: s -> sign(cos(theta)).
  // The peaks stay at +-1 for every f_f, and the wave is smooth (C-infinity) for f_f < 1:
  // the steepest slope, at the zero crossings, is 1/sqrt(1 - f_f).
  c := cos(theta);
  s := c/sqrt((1 - f_f) + f_f*c*c);
  annotation(Documentation(info="<html>
<p>Unit-amplitude periodic wave between a cosine (f_f = 0) and a square wave (f_f -&gt; 1).</p>
</html>"));
end formWave;
