# Writes ezdxf_sample.dxf (the DXF reader test reads it): a DXF from an independent writer (Debian python3-ezdxf), R2010, mm.
# Run: /usr/bin/python3 ezdxf_sample.py (then keep only ezdxf_sample.dxf). Not needed for the build.
import ezdxf, math
doc = ezdxf.new('R2010', units=4)
msp = doc.modelspace()
# a closed slot of LWPOLYLINE with bulges
msp.add_lwpolyline([(0, 0, 0, 0, 0), (40, 0, 0, 0, 1), (40, 20, 0, 0, 0), (0, 20, 0, 0, 1)], format='xyseb', close=True)
# line + arc + line chain, last line given backwards
msp.add_line((60, 0), (80, 0))
msp.add_arc((80, 10), 10, -90, 90)
msp.add_line((60, 20), (80, 20))
msp.add_circle((100, 10), 5)
msp.add_ellipse((130, 10), major_axis=(10, 0), ratio=0.5)
# rational spline: quarter circle radius 10 at (150, 0)
s = msp.add_rational_spline([(160, 0), (160, 10), (150, 10)], [1, math.sqrt(0.5), 1], degree=2, knots=[0, 0, 0, 1, 1, 1])
msp.add_open_spline([(170, 0), (175, 10), (185, -10), (190, 0)], degree=3)
msp.add_text("hello")
doc.saveas('ezdxf_sample.dxf')
