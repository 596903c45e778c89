// node mci.mjs IN.raw OUT.raw NX NY NZ SX SY SZ AXIS: ITK's MorphologicalContourInterpolator
// (npm @itk-wasm/morphological-contour-interpolation, WebAssembly under node) on a uint8
// label volume of raw samples, i fastest, along AXIS; prints the filter's seconds as JSON.
// validation/labels.py and tests/bench_fill.sh run it.
import fs from 'fs'
import { morphologicalContourInterpolationNode } from '@itk-wasm/morphological-contour-interpolation'
const [inp, out, nx, ny, nz, sx, sy, sz, axis] = process.argv.slice(2)
const size = [nx, ny, nz].map(Number)
const data = new Uint8Array(fs.readFileSync(inp))
const image = {
  imageType: { dimension: 3, componentType: 'uint8', pixelType: 'Scalar', components: 1 },
  name: 'labels', origin: [0, 0, 0], spacing: [sx, sy, sz].map(Number),
  direction: new Float64Array([1, 0, 0, 0, 1, 0, 0, 0, 1]), size, metadata: new Map(), data,
}
const t0 = process.hrtime.bigint()
const { outputImage } = await morphologicalContourInterpolationNode(image, { axis: Number(axis) })
const t1 = process.hrtime.bigint()
fs.writeFileSync(out, Buffer.from(outputImage.data.buffer, outputImage.data.byteOffset, outputImage.data.byteLength))
console.log(JSON.stringify({ seconds: Number(t1 - t0) / 1e9 }))
