// Vite builds the pages (live dashboard, recovery, pre-flight plan, the Lab and a relay's public page) into dist/, which the daemon serves.
// In development the dev server proxies the API, the KML feed and the tiles to a daemon
// (`stx serve --sim` for a simulated drone, or `stx serve`) at STX_DAEMON (default http://127.0.0.1:8080).
import { defineConfig } from "vitest/config";
import { fileURLToPath } from "node:url";

const here = (file: string): string => fileURLToPath(new URL(file, import.meta.url));

const daemon = process.env.STX_DAEMON ?? "http://127.0.0.1:8080";

export default defineConfig({
  base: "/",
  build: {
    outDir: "dist",
    emptyOutDir: true,
    // three is large; one chunk per page is fine on a LAN and keeps offline caching simple.
    chunkSizeWarningLimit: 1500,
    rollupOptions: {
      input: {
        live: here("./index.html"),
        recovery: here("./recovery.html"),
        plan: here("./plan.html"),
        lab: here("./lab.html"),
        public: here("./public.html"),
      },
    },
  },
  server: {
    host: "127.0.0.1",
    port: 5173,
    proxy: {
      "/api": { target: daemon, ws: true, changeOrigin: true },
      "/kml": { target: daemon, changeOrigin: true },
      "/tiles": { target: daemon, changeOrigin: true },
    },
  },
  test: {
    environment: "node",
    include: ["src/**/*.test.ts", "scripts/**/*.test.mjs"],
  },
});
