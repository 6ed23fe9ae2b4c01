// Reading a pane's picture back inside the page: every pane is drawn into one WebGL canvas
// over the row of panes (the renderer keeps its drawing buffer); the part of it over the
// pane's box (<div data-pane="i">, edges rounded to whole canvas pixels) is drawn into a 2D
// canvas and its pixels compared there; only counts come back.

// Defines window.__gfPanePixels(index) -> RGBA bytes of pane `index`. Call once per page.
export function installPixelReader(page) {
  return page.evaluate(() => {
    window.__gfPanePixels = (paneIndex) => {
      const box = document.querySelector(`[data-pane="${paneIndex}"]`);
      const canvas = box.closest('.gf-panes').querySelector('canvas.gf-canvas');
      const c = canvas.getBoundingClientRect();
      const b = box.getBoundingClientRect();
      const sx = canvas.width / c.width;
      const sy = canvas.height / c.height;
      const x = Math.round((b.left - c.left) * sx);
      const y = Math.round((b.top - c.top) * sy);
      const copy = document.createElement('canvas');
      copy.width = Math.round((b.right - c.left) * sx) - x;
      copy.height = Math.round((b.bottom - c.top) * sy) - y;
      const ctx = copy.getContext('2d', { willReadFrequently: true });
      ctx.drawImage(canvas, x, y, copy.width, copy.height, 0, 0, copy.width, copy.height);
      return ctx.getImageData(0, 0, copy.width, copy.height).data;
    };
  });
}

// Counts a pane's pixels: `differing` from the canvas's background (data-bg), and `matching`
// the colour rgb ([r, g, b], 0..255) within `tol` per channel (0 when rgb is null).
export function countPixels(page, paneIndex, rgb, tol = 6) {
  return page.evaluate(({ paneIndex, rgb, tol }) => {
    const px = window.__gfPanePixels(paneIndex);
    const bg = parseInt(document.querySelector(`[data-pane="${paneIndex}"]`).dataset.bg.slice(1), 16);
    const bgRgb = [(bg >> 16) & 255, (bg >> 8) & 255, bg & 255];
    const near = (i, c, t) => Math.abs(px[i] - c[0]) <= t && Math.abs(px[i + 1] - c[1]) <= t && Math.abs(px[i + 2] - c[2]) <= t;
    let differing = 0;
    let matching = 0;
    for (let i = 0; i < px.length; i += 4) {
      if (!near(i, bgRgb, 2)) differing++;
      if (rgb && near(i, rgb, tol)) matching++;
    }
    return { differing, matching, total: px.length / 4 };
  }, { paneIndex, rgb, tol });
}

// Keeps a copy of a pane's pixels in the page for diffPixels.
export function rememberPixels(page, paneIndex) {
  return page.evaluate((i) => { window.__gfRemembered = window.__gfPanePixels(i); }, paneIndex);
}

// Counts the pixels of a pane that changed since rememberPixels.
export function diffPixels(page, paneIndex) {
  return page.evaluate((i) => {
    const now = window.__gfPanePixels(i);
    const before = window.__gfRemembered;
    let differing = 0;
    for (let k = 0; k < now.length; k += 4) {
      if (now[k] !== before[k] || now[k + 1] !== before[k + 1] || now[k + 2] !== before[k + 2]) differing++;
    }
    return { differing, total: now.length / 4 };
  }, paneIndex);
}
