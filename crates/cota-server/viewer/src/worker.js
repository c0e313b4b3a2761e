// The stream in a Web Worker: fetch /stream in ranges (32 KiB first, then
// doubling), decode each step as soon as its frame is complete and post the
// points it split, with their heights, to the page. Coarse first: the page
// can draw after the first few hundred bytes.
import { StreamReader } from './decoder.js';

const FIRST_BYTES = 32 * 1024;

async function fetchRange(url, from, to) {
  let r = await fetch(url, { headers: { Range: `bytes=${from}-${to}` } });
  // 503: the stream is still being encoded (or the server is busy): wait as told.
  for (let k = 0; r.status === 503 && k < 600; k++) {
    await new Promise((ok) => setTimeout(ok, 1000 * Math.min(Number(r.headers.get('Retry-After')) || 1, 10)));
    r = await fetch(url, { headers: { Range: `bytes=${from}-${to}` } });
  }
  if (r.status !== 206 && r.status !== 200) throw new Error(`GET ${url} ${from}-${to}: HTTP ${r.status}`);
  const total = Number((r.headers.get('Content-Range') || '').split('/')[1] || r.headers.get('Content-Length'));
  const body = new Uint8Array(await r.arrayBuffer());
  return { body: r.status === 200 ? body.subarray(from) : body, total, whole: r.status === 200 };
}

function post(reader, steps, received, t0) {
  const d = reader.decoder;
  for (const info of steps) {
    const heights = new Float32Array(info.points.length);
    info.points.forEach((p, k) => {
      heights[k] = d.heightM(p);
    });
    self.postMessage(
      {
        type: 'step',
        index: info.index,
        maxErrorM: info.maxErrorM,
        points: info.points,
        heights,
        endOffset: info.endOffset,
        received,
        decodeMs: performance.now() - t0,
      },
      [info.points.buffer, heights.buffer],
    );
  }
}

async function run(url) {
  const reader = new StreamReader();
  let at = 0;
  let chunk = FIRST_BYTES;
  let total = Infinity;
  let headSent = false;
  const t0 = performance.now();
  while (at < total) {
    const r = await fetchRange(url, at, at + chunk - 1);
    total = r.total;
    at += r.body.length;
    const steps = reader.push(r.body);
    if (!headSent && reader.decoder) {
      const h = reader.decoder.header;
      self.postMessage({ type: 'head', width: h.width, height: h.height, quantum: h.quantum, steps: reader.announced, total, georef: reader.georef });
      headSent = true;
    }
    post(reader, steps, at, t0);
    if (r.whole || r.body.length === 0) break;
    chunk *= 2;
  }
  reader.finish();
  self.postMessage({ type: 'done', received: at, decodeMs: performance.now() - t0 });
}

self.onmessage = (e) => {
  if (e.data?.type === 'start') {
    run(e.data.url).catch((err) => self.postMessage({ type: 'error', message: String(err.message || err) }));
  }
};
