import { svelte } from "@sveltejs/vite-plugin-svelte";
import { defineConfig } from "vitest/config";

// The build lands inside the Python package so the wheel carries it and the daemon serves it at `/`;
// pip users need no node. `base: "./"` keeps every asset URL relative, so the page also works behind
// a path prefix (a reverse proxy, the daemon's own sub-mounts).
export default defineConfig({
  plugins: [svelte()],
  base: "./",
  build: {
    outDir: "../server/daemon/static",
    emptyOutDir: true,
    chunkSizeWarningLimit: 1200,
    reportCompressedSize: false,
  },
  server: {
    // `npm run dev` against a running `openbricks console` on its default port.
    proxy: {
      "/api": { target: "http://127.0.0.1:8765", ws: true },
      "/sim": { target: "http://127.0.0.1:8765", ws: true },
    },
  },
  test: {
    include: ["tests/**/*.test.ts"],
    environment: "node",
  },
});
