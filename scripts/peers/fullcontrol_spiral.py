"""FullControl writing the same spiral: the points of Clayloft's G-code become fc.Point steps;
only FullControl's own work (steps -> G-code text -> file) is timed."""
import sys, time, re
import fullcontrol as fc
src, out = sys.argv[1], sys.argv[2]
pts = []
x = y = z = 0.0
num = re.compile(r'([XYZE])(-?[0-9.]+)')
for line in open(src):
    if not line.startswith('G1'):
        continue
    d = dict(num.findall(line.split(';')[0].split('*')[0]))
    x = float(d.get('X', x)); y = float(d.get('Y', y)); z = float(d.get('Z', z))
    if 'E' in d:
        pts.append((x, y, z))
t0 = time.perf_counter()
steps = [fc.Extruder(on=True)] + [fc.Point(x=a, y=b, z=c) for a, b, c in pts]
g = fc.transform(steps, 'gcode', fc.GcodeControls(printer_name='generic', save_as=None,
    initialization_data={'extrusion_width': 3.0, 'extrusion_height': 0.5, 'nozzle_temp': 0,
                         'bed_temp': 0, 'print_speed': 1200}))
open(out, 'w').write(g)
t1 = time.perf_counter()
print(f"fullcontrol: {len(pts)} points, {t1 - t0:.2f} s, {len(g)} bytes")
