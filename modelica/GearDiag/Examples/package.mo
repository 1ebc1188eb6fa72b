within GearDiag;
package Examples "Machines connected from the components"
  annotation(Documentation(info="<html>
<p>PairOnShafts: GearPair from the drive train's components (the same acceleration).</p>
<p>TwoStageGearbox: two stages on three shafts, the idler's twist coupling them.</p></html>"));
end Examples;
