// Reads the multi-channel OpenEXR files that `prt bake` writes for texel transfer (docs/bundle.md, texel_transfer
// with format half or float): single-part scanline images, HALF or FLOAT channels, compression NONE, ZIPS or ZIP.
// three.js's EXRLoader decodes only R, G, B, A and Y channels into a texture, and a bake has 3 L^2 channels named
// T000.R .. T{L^2-1}.B, so the viewer reads them itself. Anything else is refused with a message, never guessed.

const kHalf = 1, kFloat = 2;
const kLinesPerChunk = { 0: 1, 2: 1, 3: 16 }; // NONE, ZIPS, ZIP

// IEEE 754 binary16 to a number (bundles' float16 layers and half-float EXR channels).
export function halfToFloat(h) {
  const sign = h & 0x8000 ? -1 : 1, exponent = (h >> 10) & 0x1f, fraction = h & 0x3ff;
  if (exponent === 0) return sign * fraction * 2 ** -24;
  if (exponent === 31) return fraction ? NaN : sign * Infinity;
  return sign * (1 + fraction / 1024) * 2 ** (exponent - 15);
}

async function inflate(bytes) {
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate'));
  return new Uint8Array(await new Response(stream).arrayBuffer());
}

// OpenEXR's ZIP filter, undone: a byte-delta predictor over the whole block, then the two halves interleaved.
function unpredict(t) {
  for (let i = 1; i < t.length; ++i) t[i] = (t[i - 1] + t[i] - 128) & 0xff;
  const out = new Uint8Array(t.length), half = (t.length + 1) >> 1;
  for (let i = 0; i < t.length; ++i) out[i] = i & 1 ? t[half + (i >> 1)] : t[i >> 1];
  return out;
}

// Parses `arrayBuffer` (the file's bytes). Returns {width, height, channels: {name: Float32Array(width*height)}},
// row 0 at the top. Throws Error naming `source` and the problem for anything outside the subset above.
export async function readExr(arrayBuffer, source) {
  const fail = (what) => { throw new Error(`${source}: ${what}`); };
  const view = new DataView(arrayBuffer), bytes = new Uint8Array(arrayBuffer);
  if (bytes.length < 8 || view.getUint32(0, true) !== 20000630) fail('not an OpenEXR file');
  if (view.getUint32(4, true) & 0x1a00) fail('tiled, deep or multi-part OpenEXR is not supported');
  let at = 8;
  const string = () => {
    const end = bytes.indexOf(0, at);
    if (end < 0) fail('truncated header');
    const text = new TextDecoder().decode(bytes.subarray(at, end));
    at = end + 1;
    return text;
  };
  const header = {};
  for (;;) {
    const name = string();
    if (!name) break;
    const type = string(), size = view.getInt32(at, true);
    at += 4;
    if (size < 0 || at + size > bytes.length) fail(`attribute ${name}: size ${size} runs past the file`);
    header[name] = { type, at, size };
    at += size;
  }
  const need = (name, type) => {
    if (!header[name] || header[name].type !== type) fail(`no ${type} attribute "${name}"`);
    return header[name];
  };
  const channels = [];
  for (let p = need('channels', 'chlist').at, end = p + header.channels.size; p < end && bytes[p];) {
    const stop = bytes.indexOf(0, p);
    const name = new TextDecoder().decode(bytes.subarray(p, stop));
    const pixelType = view.getInt32(stop + 1, true);
    if (pixelType !== kHalf && pixelType !== kFloat) fail(`channel ${name}: pixel type ${pixelType} is not half or float`);
    if (view.getInt32(stop + 9, true) !== 1 || view.getInt32(stop + 13, true) !== 1) fail(`channel ${name}: subsampled`);
    channels.push({ name, bytes: pixelType === kHalf ? 2 : 4 });
    p = stop + 17;
  }
  const compression = bytes[need('compression', 'compression').at];
  const linesPerChunk = kLinesPerChunk[compression];
  if (!linesPerChunk) fail(`compression ${compression} is not NONE, ZIPS or ZIP`);
  const box = need('dataWindow', 'box2i').at;
  const xMin = view.getInt32(box, true), yMin = view.getInt32(box + 4, true);
  const width = view.getInt32(box + 8, true) - xMin + 1, height = view.getInt32(box + 12, true) - yMin + 1;
  if (width <= 0 || height <= 0 || width * height > 1 << 26) fail(`data window of ${width} x ${height}`);

  const lineBytes = width * channels.reduce((sum, c) => sum + c.bytes, 0);
  const out = Object.fromEntries(channels.map((c) => [c.name, new Float32Array(width * height)]));
  const chunks = Math.ceil(height / linesPerChunk);
  for (let chunk = 0; chunk < chunks; ++chunk) {
    const offset = Number(view.getBigUint64(at + 8 * chunk, true));
    if (offset + 8 > bytes.length) fail(`chunk ${chunk} lies past the end of the file`);
    const y = view.getInt32(offset, true) - yMin, size = view.getInt32(offset + 4, true);
    const lines = Math.min(linesPerChunk, height - y);
    if (y < 0 || y >= height || size < 0 || offset + 8 + size > bytes.length) fail(`chunk ${chunk} is damaged`);
    let data = bytes.slice(offset + 8, offset + 8 + size);
    const expected = lines * lineBytes;
    if (compression !== 0 && size < expected) data = unpredict(await inflate(data)); // stored raw when not smaller
    if (data.length !== expected) fail(`chunk ${chunk} holds ${data.length} bytes, expected ${expected}`);
    const values = new DataView(data.buffer, data.byteOffset, data.byteLength);
    let p = 0;
    for (let line = 0; line < lines; ++line)
      for (const c of channels) {
        const target = out[c.name], row = (y + line) * width;
        for (let x = 0; x < width; ++x, p += c.bytes)
          target[row + x] = c.bytes === 2 ? halfToFloat(values.getUint16(p, true)) : values.getFloat32(p, true);
      }
  }
  return { width, height, channels: out };
}
