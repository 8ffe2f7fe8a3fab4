<!DOCTYPE PickedPoints>
<PickedPoints>
 <DocumentData>
  <DataFileName name="ball.obj"/>
 </DocumentData>
 <point x="0" y="0" z="1" name="seed0" active="1"/>
 <point x="1" y="0" z="0" name="seed1" active="1"/>
 <point x="0" y="0" z="-1" name="seed2" active="1"/>
 <point x="-1" y="0" z="0" name="seed3" active="1"/>
 <point x="0" y="1" z="0" name="tip" active="1"/>
 <point x="0" y="-1" z="0" name="off" active="0"/>
</PickedPoints>
