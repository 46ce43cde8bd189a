// Service worker for the recovery page: network first, cache as fallback, so the page's own files
// open in the field with no network. On install it caches recovery.html and the files it names
// (their names are hashed by the build, so they are read from the page, not listed here). The
// API, KML and tiles are never cached (they carry the token, and the page keeps its own copy of
// the last state in localStorage).
const CACHE = "stx-recovery-v1";
const PAGE = "recovery.html";

self.addEventListener("install", (e) => {
  e.waitUntil(
    (async () => {
      const cache = await caches.open(CACHE);
      const res = await fetch(PAGE, { cache: "no-store" });
      if (!res.ok) return;
      const html = await res.clone().text();
      await cache.put(PAGE, res);
      const assets = [...html.matchAll(/(?:src|href)="([^"#]+\.(?:js|css))"/g)].map((m) => m[1]);
      await cache.addAll(assets);
    })().then(() => self.skipWaiting()),
  );
});
self.addEventListener("activate", (e) => e.waitUntil(self.clients.claim()));
self.addEventListener("fetch", (e) => {
  const url = new URL(e.request.url);
  if (e.request.method !== "GET" || url.origin !== self.location.origin) return;
  if (/^\/(api|kml|tiles|mock)(\/|$)/.test(url.pathname)) return;
  e.respondWith(
    fetch(e.request)
      .then((res) => {
        if (res.ok) {
          const copy = res.clone();
          caches.open(CACHE).then((c) => c.put(e.request, copy));
        }
        return res;
      })
      // ignoreSearch: the page may be opened as recovery.html?token=…
      .catch(() => caches.match(e.request, { ignoreSearch: true }).then((r) => r || Response.error())),
  );
});
