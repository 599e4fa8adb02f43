#!/usr/bin/python3
"""The I/O floor: seconds GDAL needs only to read every pixel of the given rasters, block by
block (no computation). usage: io_floor.py RASTER [RASTER...]  -> prints seconds"""
import sys, time
from osgeo import gdal
gdal.UseExceptions()
start = time.perf_counter()
for path in sys.argv[1:]:
    d = gdal.Open(path)
    for b in range(1, d.RasterCount + 1):
        band = d.GetRasterBand(b)
        bx, by = band.GetBlockSize()
        for y in range(0, d.RasterYSize, by):
            rows = min(by, d.RasterYSize - y)
            band.ReadRaster(0, y, d.RasterXSize, rows)
    d = None
print("%.3f" % (time.perf_counter() - start))
