// The knot in 3D with three.js: each rod drawn as a tube of its true radius
// around its stored centreline (a bend's rods each in its own colour), a
// hitch's rigid cylinder, orbit controls (rotate, zoom, pan) and a reset.
import { InstancedMesh, Matrix4, SphereGeometry, MeshBasicMaterial, AmbientLight, Box3, CatmullRomCurve3, Color, CylinderGeometry, DirectionalLight, Group, Mesh, MeshStandardMaterial, PerspectiveCamera, Quaternion, Scene, TubeGeometry, Vector3, WebGLRenderer } from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";

/** The rods' colours in order: a one-rod knot keeps the first. */
export const ROD_COLOURS = [0x2e7dd7, 0xd55e00, 0x009e73, 0xcc79a7];

export class KnotView {
  constructor(el, radius) {
    this.el = el;
    this.radius = radius;
    this.renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    el.appendChild(this.renderer.domElement);
    this.renderer.domElement.setAttribute("role", "img");
    this.renderer.domElement.setAttribute("aria-label", "the knot's centreline as a tube of the rod's radius");
    this.scene = new Scene();
    this.camera = new PerspectiveCamera(35, 1, 1e-4, 100);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener("change", () => this.render());
    this.scene.add(new AmbientLight(0xffffff, 0.6));
    const light = new DirectionalLight(0xffffff, 1.6);
    light.position.set(1, 2, 3);
    this.scene.add(light);
    // Slightly translucent, so that the contact beads between touching strands show.
    this.materials = ROD_COLOURS.map((color) => new MeshStandardMaterial({ color, roughness: 0.45, metalness: 0.05, transparent: true, opacity: 0.75 }));
    this.mesh = null;
    this.cylinder = null;
    this.marks = null;
    this.home = null;
    this.resize();
    window.addEventListener("resize", () => this.resize());
  }

  resize() {
    const w = this.el.clientWidth || 600;
    const h = Math.max(260, Math.min(480, w * 0.75));
    this.renderer.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  /**
   * Shows the centreline `points` ([[x, y, z]...], m), one rod after the
   * other with `rods` their node counts (empty: one rod), each rod a tube in
   * its own colour (ROD_COLOURS), and the loaded contacts ([{a, b, force}])
   * as beads between the touching surfaces, coloured from blue (weakest) to
   * red (strongest force of the snapshot).
   */
  show(points, contacts = [], rods = []) {
    if (this.mesh) {
      this.scene.remove(this.mesh);
      this.mesh.children.forEach((m) => m.geometry.dispose());
    }
    if (this.marks) {
      this.scene.remove(this.marks);
      this.marks.geometry.dispose();
      this.marks = null;
    }
    if (contacts.length) {
      const largest = Math.max(...contacts.map((c) => c.force)) || 1;
      const bead = new SphereGeometry(this.radius * 0.8, 12, 8);
      this.marks = new InstancedMesh(bead, new MeshBasicMaterial(), contacts.length);
      const m = new Matrix4();
      contacts.forEach((c, i) => {
        m.makeTranslation((c.a[0] + c.b[0]) / 2, (c.a[1] + c.b[1]) / 2, (c.a[2] + c.b[2]) / 2);
        this.marks.setMatrixAt(i, m);
        const t = c.force / largest;
        this.marks.setColorAt(i, new Color().setHSL((1 - t) * 0.66, 0.9, 0.5));
      });
      this.scene.add(this.marks);
    }
    // The knot sits in the middle of the rod: frame the part away from the tails.
    const v = points.map((p) => new Vector3(p[0], p[1], p[2]));
    const counts = rods && rods.length ? rods : [v.length];
    const starts = counts.map((_, r) => counts.slice(0, r).reduce((a, b) => a + b, 0));
    this.mesh = new Group();
    counts.forEach((n, r) => {
      const curve = new CatmullRomCurve3(v.slice(starts[r], starts[r] + n));
      const geometry = new TubeGeometry(curve, Math.min(4000, n * 4), this.radius, 12, false);
      this.mesh.add(new Mesh(geometry, this.materials[r % this.materials.length]));
    });
    this.scene.add(this.mesh);
    if (!this.home) {
      // Frame the knot: the points farther than a few radii from the line
      // joining the pulled ends (one rod's two ends; the builder starts each
      // of a bend's rods at its standing end), which the straight tails are not.
      const first = v[0];
      const second = counts.length > 1 ? v[starts[1]] : v[v.length - 1];
      const axis = second.clone().sub(first).normalize();
      const off = (p) => p.clone().sub(first).sub(axis.clone().multiplyScalar(p.clone().sub(first).dot(axis))).length();
      let core = v.filter((p) => off(p) > 3 * this.radius);
      if (core.length < 2) core = v;
      const box = new Box3().setFromPoints(core);
      const size = box.getSize(new Vector3()).length() || 0.1;
      const target = box.getCenter(new Vector3());
      this.home = { target, position: target.clone().add(new Vector3(0, -1.5 * size, 0.5 * size)) };
      this.reset();
    }
    this.render();
  }

  /**
   * Draws a hitch's rigid cylinder, `{center: [x, y, z], axis: [x, y, z],
   * radius, length}` (m), grey and translucent; null or undefined: none.
   */
  setCylinder(cylinder) {
    if (this.cylinder) {
      this.scene.remove(this.cylinder);
      this.cylinder.geometry.dispose();
      this.cylinder.material.dispose();
      this.cylinder = null;
    }
    if (!cylinder) return;
    const geometry = new CylinderGeometry(cylinder.radius, cylinder.radius, cylinder.length, 48);
    const material = new MeshStandardMaterial({ color: 0x9aa0a6, roughness: 0.6, transparent: true, opacity: 0.35, depthWrite: false });
    this.cylinder = new Mesh(geometry, material);
    // CylinderGeometry's axis is y: turn it onto the cylinder's.
    const axis = new Vector3(...cylinder.axis).normalize();
    this.cylinder.quaternion.copy(new Quaternion().setFromUnitVectors(new Vector3(0, 1, 0), axis));
    this.cylinder.position.set(...cylinder.center);
    this.scene.add(this.cylinder);
    this.render();
  }

  reset() {
    if (!this.home) return;
    this.camera.position.copy(this.home.position);
    this.camera.up.set(0, 0, 1);
    this.controls.target.copy(this.home.target);
    this.controls.update();
    this.render();
  }

  render() {
    const bg = window.matchMedia && window.matchMedia("(prefers-color-scheme: dark)").matches ? 0x1b1d21 : 0xf4f6f8;
    this.scene.background = new Color(bg);
    this.renderer.render(this.scene, this.camera);
  }
}
