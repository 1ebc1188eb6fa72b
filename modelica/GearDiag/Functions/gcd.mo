within GearDiag.Functions;
function gcd "Greatest common divisor of two positive integers (Euclid, bounded loop)"
  input Integer a;
  input Integer b;
  output Integer g;
protected
  Integer x;
  Integer y;
  Integer r;
algorithm
  // rumoca rejects while-loops in functions; Euclid needs fewer than 30 steps
  // for any operands below 832040 (the 30th Fibonacci number), ample for teeth counts.
  x := a;
  y := b;
  for i in 1:30 loop
    if y > 0 then
      r := mod(x, y);
      x := y;
      y := r;
    end if;
  end for;
  g := x;
  annotation(Documentation(info="<html>
<p>Greatest common divisor of two positive integers (Euclid, bounded loop).</p>
</html>"));
end gcd;
